//! OBJ and MTL cases: a lit quad (its MTL gives an emitter) broken one way per case.

use crate::corpus::{Case, Expect, error, warning};

/// A valid OBJ: a quad under an emissive quad, both from `x.mtl`.
pub const OBJ: &str = "mtllib x.mtl\n\
v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\n\
v 0 1 0\nv 1 1 0\nv 1 1 1\nv 0 1 1\n\
vt 0 0\nvt 1 0\nvt 1 1\n\
vn 0 1 0\n\
usemtl floor\nf 1/1/1 2/2/1 3/3/1 4/1/1\n\
usemtl lamp\nf 5 8 7 6\n";

/// The library of [`OBJ`].
pub const MTL: &str = "newmtl floor\nKd 0.8 0.8 0.8\n\nnewmtl lamp\nKd 0 0 0\nKe 1 1 1\n";

/// A case with `x.obj` = `obj` and `x.mtl` = `mtl`.
fn obj(name: &str, obj: impl Into<Vec<u8>>, mtl: &str, expect: Expect) -> Case {
    Case::new("obj", name)
        .file("x.obj", obj)
        .file("x.mtl", mtl)
        .scene("x.obj", expect)
}

/// [`OBJ`] with `line` appended.
fn plus(line: &str) -> String {
    format!("{OBJ}{line}\n")
}

/// Deterministic pseudo-random bytes (xorshift), `n` of them.
pub fn junk(n: usize, seed: u64) -> Vec<u8> {
    let mut x = seed | 1;
    (0..n)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 24) as u8
        })
        .collect()
}

/// Every OBJ/MTL case.
pub fn cases() -> Vec<Case> {
    let f = "x.obj";
    let huge = "9".repeat(1 << 20);
    let mut junk_no_nul = junk(64 << 10, 7);
    for b in &mut junk_no_nul {
        if *b == 0 {
            *b = 0xff;
        }
    }
    vec![
        obj("valid", OBJ, MTL, Expect::Success),
        obj(
            "index_zero",
            plus("f 0 1 2"),
            MTL,
            error(&[f, "line 18", "index 0"]),
        ),
        obj(
            "index_past_end",
            plus("f 1 2 99"),
            MTL,
            error(&[f, "line 18", "99"]),
        ),
        obj(
            "negative_index_past_start",
            plus("f -1 -2 -9"),
            MTL,
            error(&[f, "line 18", "-9"]),
        ),
        obj(
            "index_not_an_integer",
            plus("f 1.5 2 3"),
            MTL,
            error(&[f, "line 18", "1.5"]),
        ),
        obj(
            "index_beyond_i64",
            plus("f 99999999999999999999999 1 2"),
            MTL,
            error(&[f, "line 18"]),
        ),
        obj(
            "uv_index_past_end",
            plus("f 1/9 2/1 3/1"),
            MTL,
            error(&[f, "line 18", "texture coordinate"]),
        ),
        obj(
            "normal_index_past_end",
            plus("f 1//9 2//1 3//1"),
            MTL,
            error(&[f, "line 18", "normal"]),
        ),
        obj(
            "face_with_one_vertex",
            plus("f 1"),
            MTL,
            error(&[f, "line 18", "corners"]),
        ),
        obj(
            "face_with_two_vertices",
            plus("f 1 2"),
            MTL,
            error(&[f, "line 18", "corners"]),
        ),
        obj(
            "vertex_nan",
            format!("v nan 0 0\n{OBJ}"),
            MTL,
            error(&[f, "line 1", "not finite"]),
        ),
        obj(
            "vertex_inf",
            format!("v 0 -inf 0\n{OBJ}"),
            MTL,
            error(&[f, "line 1", "not finite"]),
        ),
        obj(
            "vertex_1e39",
            format!("v 0 0 1e39\n{OBJ}"),
            MTL,
            error(&[f, "line 1", "not finite"]),
        ),
        obj(
            "vertex_3e38",
            format!("v 3e38 0 0\n{OBJ}f -1 1 2\n"),
            MTL,
            error(&[f, "instance 0", "beyond", "1e18"]),
        ),
        obj(
            "vertex_too_few_numbers",
            format!("v 1 2\n{OBJ}"),
            MTL,
            error(&[f, "line 1", "expected 3"]),
        ),
        obj(
            "vertex_not_a_number",
            format!("v 1 2 three\n{OBJ}"),
            MTL,
            error(&[f, "line 1", "three"]),
        ),
        obj(
            "uv_nan",
            format!("vt nan 0\n{OBJ}"),
            MTL,
            error(&[f, "line 1", "not finite"]),
        ),
        obj(
            "normal_inf",
            format!("vn inf 0 0\n{OBJ}"),
            MTL,
            error(&[f, "line 1", "not finite"]),
        ),
        obj(
            "one_megabyte_number",
            format!("v {huge} 0 0\n{OBJ}"),
            MTL,
            error(&[f, "line 1"]),
        ),
        obj(
            "one_megabyte_keyword",
            format!("{huge}\n{OBJ}"),
            MTL,
            warning(&[f, "ignored"]),
        ),
        obj(
            "one_megabyte_material_name",
            format!("{OBJ}usemtl {huge}\nf 1 2 3\n"),
            MTL,
            warning(&[f, "unknown material"]),
        ),
        obj("binary_junk", junk(64 << 10, 3), MTL, error(&[f, "binary"])),
        obj(
            "binary_junk_without_nul",
            junk_no_nul,
            MTL,
            error(&[f, "non-text"]),
        ),
        obj("empty_file", "", MTL, warning(&[f, "no faces"])),
        obj(
            "only_vertices",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\n",
            MTL,
            warning(&[f, "no faces"]),
        ),
        obj(
            "unknown_statements",
            plus("curv 0 1 2\nl 1 2"),
            MTL,
            warning(&[f, "curv"]),
        ),
        obj(
            "unknown_material",
            plus("usemtl marble\nf 1 2 3"),
            MTL,
            warning(&[f, "marble"]),
        ),
        Case::new("obj", "missing_mtl")
            .file("x.obj", OBJ)
            .scene("x.obj", warning(&[f, "line 1", "x.mtl"])),
        Case::new("obj", "mtllib_is_a_folder")
            .file("x.obj", OBJ)
            .dir("x.mtl")
            .scene("x.obj", warning(&[f, "line 1", "x.mtl"])),
        Case::new("obj", "mtllib_one_megabyte_name")
            .file(
                "x.obj",
                OBJ.replace("mtllib x.mtl", &format!("mtllib {huge}.mtl")),
            )
            .scene("x.obj", warning(&[f, "line 1", "not readable"])),
        obj(
            "map_kd_one_megabyte_name",
            OBJ,
            &format!("newmtl floor\nmap_Kd {huge}.png\n"),
            warning(&[f, "x.mtl line 2", "map_Kd", "file name"]),
        ),
        Case::new("obj", "mtllib_is_a_pipe")
            .file("x.obj", OBJ)
            .fifo("x.mtl")
            .scene(
                "x.obj",
                warning(&[f, "line 1", "x.mtl", "not a regular file"]),
            ),
        Case::new("obj", "mtllib_is_dev_zero")
            .file("x.obj", OBJ.replace("mtllib x.mtl", "mtllib /dev/zero"))
            .scene(
                "x.obj",
                warning(&[f, "line 1", "/dev/zero", "not a regular file"]),
            ),
        Case::new("obj", "scene_is_a_link_to_dev_zero")
            .link("x.obj", "/dev/zero")
            .scene("x.obj", error(&[f, "not a regular file"])),
        Case::new("obj", "scene_is_a_pipe")
            .fifo("x.obj")
            .scene("x.obj", error(&[f, "not a regular file"])),
        Case::new("obj", "scene_is_a_folder")
            .dir("x.obj")
            .scene("x.obj", error(&[f, "not a regular file"])),
        Case::new("obj", "scene_missing").scene("x.obj", error(&[f, "No such file"])),
        obj(
            "mtl_kd_nan",
            OBJ,
            "newmtl floor\nKd nan 0 0\n",
            error(&[f, "x.mtl line 2", "Kd"]),
        ),
        obj(
            "mtl_kd_negative",
            OBJ,
            "newmtl floor\nKd -0.5 0.5 0.5\n",
            error(&[f, "x.mtl line 2", "Kd"]),
        ),
        obj(
            "mtl_kd_above_one_is_clamped",
            OBJ,
            "newmtl floor\nKd 2 2 2\n",
            Expect::Success,
        ),
        obj(
            "mtl_ke_1e39",
            OBJ,
            "newmtl lamp\nKe 1e39 1 1\n",
            error(&[f, "x.mtl line 2", "Ke"]),
        ),
        obj(
            "mtl_ke_1e36",
            OBJ,
            "newmtl lamp\nKe 1e36 1 1\n",
            error(&[f, "light power", "1e30"]),
        ),
        obj(
            "mtl_ke_negative",
            OBJ,
            "newmtl lamp\nKe -1 -1 -1\n",
            error(&[f, "x.mtl line 2", "Ke"]),
        ),
        obj(
            "mtl_ns_negative",
            OBJ,
            "newmtl floor\nNs -1\n",
            error(&[f, "x.mtl line 2", "Ns"]),
        ),
        obj(
            "mtl_d_2",
            OBJ,
            "newmtl floor\nd 2\n",
            error(&[f, "x.mtl line 2", "d 2"]),
        ),
        obj(
            "mtl_map_without_file",
            OBJ,
            "newmtl floor\nmap_Kd\n",
            error(&[f, "x.mtl line 2", "map_kd"]),
        ),
        obj(
            "mtl_binary_junk",
            OBJ,
            &String::from_utf8_lossy(&junk(4096, 5)),
            warning(&[f, "x.mtl", "binary data", "MTL"]),
        ),
        obj(
            "mtl_one_megabyte_name",
            OBJ,
            &format!("newmtl {huge}\nKd 0.5 0.5 0.5\nKs 2 2 2\n"),
            warning(&[f, "x.mtl"]),
        ),
    ]
}
