//! Texture cases, each through an MTL `map_Kd` and a glTF image: a warning naming the
//! file (the material keeps its factors), an error with `--strict`.

use crate::corpus::Case;
use crate::corpus::{gltf, obj};
use serde_json::json;

/// CRC-32 (IEEE) as PNG chunks use it.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// A valid `w × h` RGB PNG.
pub fn png(w: u32, h: u32) -> Vec<u8> {
    let img = image::RgbImage::from_fn(w, h, |x, y| image::Rgb([x as u8, y as u8, 128]));
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png)
        .expect("PNG encoding");
    out.into_inner()
}

/// A 1×1 PNG whose header (with a correct CRC) claims `w × h` pixels: a decoder that
/// believed it would allocate w·h·3 bytes.
pub fn png_claiming(w: u32, h: u32) -> Vec<u8> {
    let mut b = png(1, 1);
    // Signature (8), IHDR length (4), "IHDR" (4), width, height, …, CRC at 29.
    b[16..20].copy_from_slice(&w.to_be_bytes());
    b[20..24].copy_from_slice(&h.to_be_bytes());
    let crc = crc32(&b[12..29]);
    b[29..33].copy_from_slice(&crc.to_be_bytes());
    b
}

/// The two cases of one texture file `name` with `bytes` (`None`: no such file;
/// `Err(target)`: a symbolic link to `target`): `obj/NAME` reads it through `map_Kd`,
/// `gltf/NAME` as a glTF image. `mentions` are the words every message has besides the
/// scene and the texture file.
fn texture(
    case: &str,
    name: &str,
    bytes: Option<Result<Vec<u8>, &str>>,
    mentions: &[&str],
) -> Vec<Case> {
    let add = |mut c: Case| {
        match &bytes {
            Some(Ok(b)) => c = c.file(name, b.clone()),
            Some(Err(target)) => c = c.link(name, target),
            None => {}
        }
        c
    };
    let mut obj_words = vec!["x.obj", "map_Kd", name];
    obj_words.extend_from_slice(mentions);
    let mut gltf_words = vec!["x.gltf", "image 0", name];
    gltf_words.extend_from_slice(mentions);
    let mtl = format!("newmtl floor\nKd 0.8 0.8 0.8\nmap_Kd {name}\n\nnewmtl lamp\nKe 1 1 1\n");
    let mut doc = gltf::doc();
    doc["images"] = json!([{"uri": name}]);
    doc["textures"] = json!([{"source": 0}]);
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
    vec![
        add(Case::new("texture", &format!("obj_{case}"))
            .file("x.obj", obj::OBJ)
            .file("x.mtl", mtl))
        .lenient_unless_strict("x.obj", &obj_words),
        add(Case::new("texture", &format!("gltf_{case}"))
            .file("x.gltf", serde_json::to_vec(&doc).expect("JSON"))
            .file("tri.bin", gltf::bin()))
        .lenient_unless_strict("x.gltf", &gltf_words),
    ]
}

/// Every texture case.
pub fn cases() -> Vec<Case> {
    let valid = png(16, 16);
    let mut c = vec![
        Case::new("texture", "obj_valid_png")
            .file("x.obj", obj::OBJ)
            .file(
                "x.mtl",
                "newmtl floor\nmap_Kd t.png\n\nnewmtl lamp\nKe 1 1 1\n",
            )
            .file("t.png", valid.clone())
            .scene_with("x.obj", &["--strict"], crate::corpus::Expect::Success),
    ];
    c.extend(texture("missing", "t.png", None, &["No such file"]));
    c.extend(texture("zero_bytes", "t.png", Some(Ok(Vec::new())), &[]));
    c.extend(texture(
        "truncated_png",
        "t.png",
        Some(Ok(valid[..valid.len() / 2].to_vec())),
        &[],
    ));
    c.extend(texture(
        "decompression_bomb",
        "t.png",
        Some(Ok(png_claiming(100_000, 100_000))),
        &["100000×100000", "1024 MiB"],
    ));
    // Issue 38: a header within the decoder's own limit (300 MB as 8-bit RGB) that is
    // 1144 MiB as the linear RGB illume keeps: refused on its header, saying the limit.
    c.extend(texture(
        "png_header_claims_10000_squared",
        "t.png",
        Some(Ok(png_claiming(10_000, 10_000))),
        &["10000×10000", "1024 MiB"],
    ));
    c.extend(texture(
        "png_header_claims_u32_max",
        "t.png",
        Some(Ok(png_claiming(u32::MAX >> 1, 1))),
        &[],
    ));
    c.extend(texture(
        "random_bytes",
        "t.tga",
        Some(Ok(obj::junk(3000, 11))),
        &[],
    ));
    c.extend(texture(
        "text_named_jpg",
        "t.jpg",
        Some(Ok(b"this is not a JPEG".to_vec())),
        &[],
    ));
    c.extend(
        texture("folder", "t.png", None, &[])
            .into_iter()
            .map(|c| c.dir("t.png")),
    );
    c.extend(
        texture("pipe", "t.png", None, &["not a regular file"])
            .into_iter()
            .map(|c| c.fifo("t.png")),
    );
    c.extend(texture(
        "dev_zero",
        "t.png",
        Some(Err("/dev/zero")),
        &["not a regular file"],
    ));
    c
}
