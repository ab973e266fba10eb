//! PLY cases: ASCII and binary little-endian files with a triangle, broken one way each.

use crate::corpus::{Case, Expect, error, warning};

/// The header of an ASCII PLY with `vertices` vertices (x y z floats) and `faces` faces.
fn ascii_header(vertices: &str, faces: &str) -> String {
    format!(
        "ply\nformat ascii 1.0\nelement vertex {vertices}\nproperty float x\nproperty float y\n\
         property float z\nelement face {faces}\nproperty list uchar int vertex_indices\nend_header\n"
    )
}

/// A valid ASCII triangle.
fn ascii() -> String {
    format!("{}0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", ascii_header("3", "1"))
}

/// A binary little-endian PLY: header with `count_type` list counts, then `body`.
fn binary(vertices: u32, faces: u32, count_type: &str, body: &[u8]) -> Vec<u8> {
    let mut b = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {vertices}\nproperty float x\n\
         property float y\nproperty float z\nelement face {faces}\n\
         property list {count_type} int vertex_indices\nend_header\n"
    )
    .into_bytes();
    b.extend_from_slice(body);
    b
}

/// The body of a valid binary triangle (uchar list counts).
fn binary_body() -> Vec<u8> {
    let mut b = Vec::new();
    for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for x in v {
            b.extend_from_slice(&x.to_le_bytes());
        }
    }
    b.push(3);
    for i in [0i32, 1, 2] {
        b.extend_from_slice(&i.to_le_bytes());
    }
    b
}

fn ply(name: &str, bytes: impl Into<Vec<u8>>, expect: Expect) -> Case {
    Case::new("ply", name)
        .file("x.ply", bytes)
        .scene("x.ply", expect)
}

/// Every PLY case.
pub fn cases() -> Vec<Case> {
    let f = "x.ply";
    let valid_binary = binary(3, 1, "uchar", &binary_body());
    let mut nan_binary = binary_body();
    nan_binary[4..8].copy_from_slice(&f32::NAN.to_le_bytes());
    // A face claiming 4 294 967 295 corners (uint count), the file ending after one.
    let mut huge_list = binary_body()[..36].to_vec();
    huge_list.extend_from_slice(&u32::MAX.to_le_bytes());
    huge_list.extend_from_slice(&0i32.to_le_bytes());
    let huge = "x".repeat(1 << 20);
    vec![
        ply("valid_ascii", ascii(), Expect::Success),
        ply("valid_binary", valid_binary.clone(), Expect::Success),
        ply(
            "first_line_not_ply",
            ascii().replacen("ply", "plx", 1),
            error(&[f, "header line 1"]),
        ),
        ply("empty_file", "", error(&[f, "header line 1"])),
        ply(
            "no_end_header",
            "ply\nformat ascii 1.0\nelement vertex 3\n",
            error(&[f, "end_header"]),
        ),
        ply(
            "no_format",
            ascii().replace("format ascii 1.0\n", ""),
            error(&[f, "format"]),
        ),
        ply(
            "unknown_format",
            ascii().replace("ascii 1.0", "binary_middle_endian 1.0"),
            error(&[f, "header line 2", "binary_middle_endian"]),
        ),
        ply(
            "version_2",
            ascii().replace("ascii 1.0", "ascii 2.0"),
            error(&[f, "header line 2", "2.0"]),
        ),
        ply(
            "unknown_property_type",
            ascii().replace("property float y", "property float128 y"),
            error(&[f, "header line 5", "float128"]),
        ),
        ply(
            "float_list_count",
            ascii().replace("list uchar int", "list float int"),
            error(&[f, "header line 8", "float"]),
        ),
        ply(
            "unknown_list_item_type",
            ascii().replace("list uchar int", "list uchar pointer"),
            error(&[f, "header line 8", "pointer"]),
        ),
        ply(
            "property_before_element",
            "ply\nformat ascii 1.0\nproperty float x\nend_header\n",
            error(&[f, "header line 3"]),
        ),
        ply(
            "unknown_keyword",
            ascii().replace("element face", "elephant face"),
            error(&[f, "header line 7", "elephant"]),
        ),
        ply(
            "element_count_negative",
            ascii().replace("element vertex 3", "element vertex -3"),
            error(&[f, "header line 3", "count"]),
        ),
        ply(
            "element_count_beyond_u64",
            ascii().replace("element vertex 3", "element vertex 99999999999999999999999"),
            error(&[f, "header line 3", "count"]),
        ),
        ply(
            "vertex_count_beyond_data_ascii",
            ascii().replace("element vertex 3", "element vertex 1000"),
            error(&[f, "vertex", "truncated"]),
        ),
        ply(
            "vertex_count_u64_max_binary",
            binary(u32::MAX, 1, "uchar", &binary_body())
                .into_iter()
                .collect::<Vec<u8>>(),
            error(&[f, "vertex", "truncated"]),
        ),
        ply(
            "face_count_beyond_data_binary",
            binary(3, 1_000_000, "uchar", &binary_body()),
            error(&[f, "face 1", "truncated"]),
        ),
        ply(
            "truncated_binary",
            valid_binary[..valid_binary.len() - 7].to_vec(),
            error(&[f, "face 0", "truncated"]),
        ),
        ply(
            "huge_list_count",
            binary(3, 1, "uint", &huge_list),
            error(&[f, "face 0", "truncated"]),
        ),
        ply(
            "list_count_negative",
            format!("{}0 0 0\n1 0 0\n0 1 0\n-3 0 1 2\n", ascii_header("3", "1"))
                .replace("list uchar int", "list char int"),
            error(&[f, "face 0", "negative"]),
        ),
        ply(
            "ascii_nan",
            format!("{}0 nan 0\n1 0 0\n0 1 0\n3 0 1 2\n", ascii_header("3", "1")),
            error(&[f, "vertex 0", "not finite"]),
        ),
        ply(
            "ascii_1e39",
            format!(
                "{}0 0 0\n1e39 0 0\n0 1 0\n3 0 1 2\n",
                ascii_header("3", "1")
            ),
            error(&[f, "vertex 1", "not finite"]),
        ),
        ply(
            "binary_nan",
            binary(3, 1, "uchar", &nan_binary),
            error(&[f, "vertex 0", "not finite"]),
        ),
        ply(
            "ascii_not_a_number",
            format!(
                "{}0 zero 0\n1 0 0\n0 1 0\n3 0 1 2\n",
                ascii_header("3", "1")
            ),
            error(&[f, "vertex 0", "zero"]),
        ),
        ply(
            "ascii_index_not_an_integer",
            format!("{}0 0 0\n1 0 0\n0 1 0\n3 0 1.5 2\n", ascii_header("3", "1")),
            error(&[f, "face 0", "1.5"]),
        ),
        ply(
            "index_out_of_range",
            format!("{}0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", ascii_header("3", "1")),
            error(&[f, "face 0", "out of range"]),
        ),
        ply(
            "face_with_two_corners",
            format!(
                "{}0 0 0\n1 0 0\n0 1 0\n2 0 1\n3 0 1 2\n",
                ascii_header("3", "2")
            ),
            warning(&[f, "fewer than 3"]),
        ),
        ply(
            "no_vertex_element",
            "ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n",
            error(&[f, "no vertex element"]),
        ),
        ply(
            "vertex_without_z",
            ascii().replace("property float z\n", ""),
            error(&[f, "x, y or z"]),
        ),
        ply(
            "face_without_list",
            ascii().replace("property list uchar int vertex_indices", "property int v"),
            error(&[f, "list"]),
        ),
        ply(
            "normals_nan",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
             property float z\nproperty float nx\nproperty float ny\nproperty float nz\n\
             element face 1\nproperty list uchar int vertex_indices\nend_header\n\
             0 0 0 nan 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n",
            warning(&[f, "normals"]),
        ),
        ply(
            "uv_nan",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
             property float z\nproperty float u\nproperty float v\n\
             element face 1\nproperty list uchar int vertex_indices\nend_header\n\
             0 0 0 nan 0\n1 0 0 0 0\n0 1 0 0 0\n3 0 1 2\n",
            error(&[f, "vertex 0", "not finite"]),
        ),
        ply(
            "binary_junk",
            crate::corpus::obj::junk(4096, 9),
            error(&[f, "header line 1"]),
        ),
        ply(
            "one_megabyte_header_token",
            ascii().replace("element face", &format!("{huge} face")),
            error(&[f, "header line 7"]),
        ),
        ply(
            "one_megabyte_body_token",
            format!(
                "{}0 {huge} 0\n1 0 0\n0 1 0\n3 0 1 2\n",
                ascii_header("3", "1")
            ),
            error(&[f, "vertex 0"]),
        ),
        ply(
            "data_after_the_end",
            format!("{}7 7 7\n", ascii()),
            warning(&[f, "ignored"]),
        ),
        ply(
            "no_faces",
            format!("{}0 0 0\n", ascii_header("1", "0")),
            Expect::Success,
        ),
    ]
}
