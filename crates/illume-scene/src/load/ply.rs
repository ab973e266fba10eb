//! PLY (Stanford polygon file) loader: ASCII, binary little-endian and binary
//! big-endian.
//!
//! Hand-written: the `ply-rs` crate is unmaintained and panics on malformed input, and
//! the subset needed here (a header, fixed-size scalars, lists) is small.
//!
//! What is read: the `vertex` element's `x y z`, optional `nx ny nz` and optional
//! texture coordinates (`u v`, `s t`, `texture_u texture_v` or `texture_s texture_t`; v
//! is flipped to illume's top-row convention, v' = 1 − v), and the `face` element's
//! index list (`vertex_indices` or `vertex_index`, else its first list property) with any
//! count and index types; polygons are fan-triangulated. Every other property
//! (`confidence`, `intensity`, `flags`, …) and element is read past and ignored. Faces
//! with fewer than three corners are skipped with a warning. The scene is one mesh with
//! one default material (albedo 0.8, two-sided), placed at the identity, with the camera
//! of [`default_camera_for_bounds`].
//!
//! Errors name the file and the place: the header line, or the element and its index
//! plus the line (ASCII) or byte offset (binary) where reading failed.

use super::{LoadError, default_camera_for_bounds, excerpt, read_file};
use crate::animation::Trs;
use crate::builtin::SceneBuilder;
use crate::model::{Material, Mesh, Scene};
use illume_core::{Vec2, Vec3};
use std::path::Path;

/// Encoding of the body.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Format {
    Ascii,
    BinaryLittleEndian,
    BinaryBigEndian,
}

/// Scalar types of PLY properties.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Self::I8,
            "uchar" | "uint8" => Self::U8,
            "short" | "int16" => Self::I16,
            "ushort" | "uint16" => Self::U16,
            "int" | "int32" => Self::I32,
            "uint" | "uint32" => Self::U32,
            "float" | "float32" => Self::F32,
            "double" | "float64" => Self::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }
}

/// A property: a scalar, or a list with its count and item types.
#[derive(Clone, Copy, Debug)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

struct Property {
    name: String,
    kind: Kind,
}

struct Element {
    name: String,
    count: usize,
    properties: Vec<Property>,
}

/// Reads values from the body, ASCII or binary, and says where it is.
enum Body<'a> {
    Ascii {
        text: &'a [u8],
        pos: usize,
        line: usize,
    },
    Binary {
        data: &'a [u8],
        pos: usize,
        big_endian: bool,
    },
}

/// A place in the body: a line (ASCII) or a byte offset (binary).
#[derive(Clone, Copy)]
enum Mark {
    Line(usize),
    Offset(usize),
}

impl std::fmt::Display for Mark {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Mark::Line(l) => write!(f, "line {l}"),
            Mark::Offset(o) => write!(f, "byte offset {o}"),
        }
    }
}

impl Body<'_> {
    /// Where the next value starts: `line N` or `byte offset N`.
    fn place(&self) -> String {
        self.mark().to_string()
    }

    /// The current line (ASCII: of the last value read) or byte offset (binary).
    fn mark(&self) -> Mark {
        match self {
            Body::Ascii { line, .. } => Mark::Line(*line),
            Body::Binary { pos, .. } => Mark::Offset(*pos),
        }
    }

    /// Reads one value of type `ty` as `f64` (exact for every PLY integer type).
    fn read(&mut self, ty: Scalar) -> Result<f64, String> {
        match self {
            Body::Ascii { text, pos, line } => {
                while *pos < text.len() && text[*pos].is_ascii_whitespace() {
                    if text[*pos] == b'\n' {
                        *line += 1;
                    }
                    *pos += 1;
                }
                let start = *pos;
                while *pos < text.len() && !text[*pos].is_ascii_whitespace() {
                    *pos += 1;
                }
                let token = text.get(start..*pos).unwrap_or(&[]);
                if token.is_empty() {
                    return Err("unexpected end of file (truncated?)".into());
                }
                let s = std::str::from_utf8(token)
                    .map_err(|_| "value is not ASCII text".to_string())?;
                let x: f64 = s
                    .parse()
                    .map_err(|_| format!("'{}' is not a number", excerpt(s)))?;
                if !matches!(ty, Scalar::F32 | Scalar::F64) && x.fract() != 0.0 {
                    return Err(format!(
                        "'{}' is not an integer but the property is {ty:?}",
                        excerpt(s)
                    ));
                }
                Ok(x)
            }
            Body::Binary {
                data,
                pos,
                big_endian,
            } => {
                let n = ty.size();
                let bytes = data
                    .get(*pos..*pos + n)
                    .ok_or_else(|| format!("file ends after {} bytes (truncated)", data.len()))?;
                let mut b = [0u8; 8];
                b[..n].copy_from_slice(bytes);
                if *big_endian {
                    b[..n].reverse();
                }
                *pos += n;
                Ok(match ty {
                    Scalar::I8 => b[0] as i8 as f64,
                    Scalar::U8 => b[0] as f64,
                    Scalar::I16 => i16::from_le_bytes([b[0], b[1]]) as f64,
                    Scalar::U16 => u16::from_le_bytes([b[0], b[1]]) as f64,
                    Scalar::I32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                    Scalar::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                    Scalar::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                    Scalar::F64 => f64::from_le_bytes(b),
                })
            }
        }
    }
}

/// The parsed header and where the body starts.
struct Header {
    format: Format,
    elements: Vec<Element>,
    body_offset: usize,
    body_first_line: usize,
}

fn parse_header(path: &Path, bytes: &[u8]) -> Result<Header, LoadError> {
    let err = |line: usize, m: String| LoadError::malformed(path, format!("header line {line}"), m);
    let mut pos = 0;
    let mut line_no = 0;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        line_no += 1;
        if pos >= bytes.len() {
            return Err(err(line_no, "file ends before 'end_header'".into()));
        }
        let end = bytes[pos..]
            .iter()
            .position(|&c| c == b'\n')
            .map(|k| pos + k)
            .unwrap_or(bytes.len());
        let raw = bytes.get(pos..end).unwrap_or(&[]);
        pos = (end + 1).min(bytes.len());
        let line = std::str::from_utf8(raw)
            .map_err(|_| err(line_no, "header line is not ASCII text".into()))?
            .trim();
        let mut tokens = line.split_whitespace();
        let keyword = tokens.next().unwrap_or("");
        if line_no == 1 {
            if line != "ply" {
                return Err(err(1, "not a PLY file (first line is not 'ply')".into()));
            }
            continue;
        }
        match keyword {
            "" | "comment" | "obj_info" => {}
            "format" => {
                let f = tokens.next().unwrap_or("");
                let version = tokens.next().unwrap_or("");
                format = Some(match f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::BinaryLittleEndian,
                    "binary_big_endian" => Format::BinaryBigEndian,
                    _ => return Err(err(line_no, format!("unknown format '{}'", excerpt(f)))),
                });
                if version != "1.0" {
                    return Err(err(
                        line_no,
                        format!(
                            "unsupported PLY version '{}' (expected 1.0)",
                            excerpt(version)
                        ),
                    ));
                }
            }
            "element" => {
                let name = tokens
                    .next()
                    .ok_or_else(|| err(line_no, "element without a name".into()))?;
                let count = tokens
                    .next()
                    .and_then(|c| c.parse::<usize>().ok())
                    .ok_or_else(|| {
                        err(
                            line_no,
                            format!("element '{}' without a valid count", excerpt(name)),
                        )
                    })?;
                elements.push(Element {
                    name: name.into(),
                    count,
                    properties: Vec::new(),
                });
            }
            "property" => {
                let element = elements
                    .last_mut()
                    .ok_or_else(|| err(line_no, "property before any element".into()))?;
                let t = tokens.next().unwrap_or("");
                let kind = if t == "list" {
                    let c = tokens.next().unwrap_or("");
                    let i = tokens.next().unwrap_or("");
                    let count = Scalar::parse(c).ok_or_else(|| {
                        err(line_no, format!("unknown list count type '{}'", excerpt(c)))
                    })?;
                    if matches!(count, Scalar::F32 | Scalar::F64) {
                        return Err(err(
                            line_no,
                            format!("list count type '{c}' is not an integer type"),
                        ));
                    }
                    let item = Scalar::parse(i).ok_or_else(|| {
                        err(line_no, format!("unknown list item type '{}'", excerpt(i)))
                    })?;
                    Kind::List { count, item }
                } else {
                    Kind::Scalar(Scalar::parse(t).ok_or_else(|| {
                        err(line_no, format!("unknown property type '{}'", excerpt(t)))
                    })?)
                };
                let name = tokens
                    .next()
                    .ok_or_else(|| err(line_no, "property without a name".into()))?;
                element.properties.push(Property {
                    name: name.into(),
                    kind,
                });
            }
            "end_header" => break,
            other => {
                return Err(err(
                    line_no,
                    format!("unknown header keyword '{}'", excerpt(other)),
                ));
            }
        }
    }
    let format = format.ok_or_else(|| err(line_no, "no 'format' line before end_header".into()))?;
    Ok(Header {
        format,
        elements,
        body_offset: pos,
        body_first_line: line_no + 1,
    })
}

pub(super) fn load(path: &Path) -> Result<Scene, LoadError> {
    let bytes = read_file(path)?;
    let header = parse_header(path, &bytes)?;
    let data = bytes.get(header.body_offset..).unwrap_or(&[]);
    let mut body = match header.format {
        Format::Ascii => Body::Ascii {
            text: data,
            pos: 0,
            line: header.body_first_line,
        },
        Format::BinaryLittleEndian => Body::Binary {
            data: &bytes,
            pos: header.body_offset,
            big_endian: false,
        },
        Format::BinaryBigEndian => Body::Binary {
            data: &bytes,
            pos: header.body_offset,
            big_endian: true,
        },
    };
    let mut warnings = Vec::new();
    let Elements {
        positions,
        normals,
        uvs,
        polygons,
    } = read_elements(path, &header, &mut body)?;
    if let Body::Ascii { text, pos, line } = &body
        && text
            .get(*pos..)
            .is_some_and(|rest| rest.iter().any(|c| !c.is_ascii_whitespace()))
    {
        warnings.push(format!(
            "{}: line {line}: data after the last element ignored",
            path.display()
        ));
    }

    let mut mesh = Mesh {
        name: path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "ply".into()),
        ..Default::default()
    };
    let skipped = triangulate(path, positions.len(), &polygons, &mut mesh.indices)?;
    if skipped > 0 {
        warnings.push(format!(
            "{}: {skipped} faces with fewer than 3 corners skipped",
            path.display()
        ));
    }
    if normals
        .iter()
        .all(|v| v.length_squared() > 0.0 && v.is_finite())
    {
        mesh.normals = normals.into_iter().map(|v| v.normalize()).collect();
    } else {
        warnings.push(format!(
            "{}: some vertex normals are zero or not finite; normals dropped",
            path.display()
        ));
    }
    mesh.positions = positions;
    mesh.uvs = uvs;

    let mut b = SceneBuilder::new();
    for w in warnings {
        b.warn(w);
    }
    let material = b.material(Material {
        name: "ply_default".into(),
        ..Material::default()
    });
    mesh.triangle_materials = vec![material; mesh.indices.len()];
    let name = mesh.name.clone();
    let mesh = b.mesh(mesh);
    b.placed(&name, mesh, Trs::IDENTITY, false);
    let mut scene = b.finish(&path.to_string_lossy());
    default_camera_for_bounds(&mut scene);
    Ok(scene)
}

/// The vertices and faces of a PLY body.
struct Elements {
    positions: Vec<Vec3>,
    /// One per position when the vertex element has nx, ny, nz; else empty.
    normals: Vec<Vec3>,
    /// One per position when the vertex element has texture coordinates; else empty.
    uvs: Vec<Vec2>,
    /// Each face's (index, place, corner indices), kept until every vertex is known.
    polygons: Vec<(usize, Mark, Vec<f64>)>,
}

/// Which properties of an element illume reads: the first `vertex` element's position,
/// normal and texture coordinates, the first `face` element's index list.
struct Layout {
    xyz: Option<[usize; 3]>,
    nxyz: Option<[usize; 3]>,
    uv: Option<[usize; 2]>,
    index_list: Option<usize>,
}

/// Reads every element of the body (checked: finite positions and texture
/// coordinates); an error without a vertex element.
fn read_elements(path: &Path, header: &Header, body: &mut Body<'_>) -> Result<Elements, LoadError> {
    let mut positions: Vec<Vec3> = Vec::new();
    let mut normals: Vec<Vec3> = Vec::new();
    let mut uvs: Vec<Vec2> = Vec::new();
    // (face index, corner indices) kept until every vertex is known.
    let mut polygons: Vec<(usize, Mark, Vec<f64>)> = Vec::new();
    let mut seen_vertex = false;
    let mut seen_face = false;
    for element in &header.elements {
        let is_vertex = element.name == "vertex" && !seen_vertex;
        let is_face = element.name == "face" && !seen_face;
        seen_vertex |= is_vertex;
        seen_face |= is_face;
        let Layout {
            xyz,
            nxyz,
            uv,
            index_list,
        } = layout(path, element, is_vertex, is_face)?;
        if element.properties.is_empty() {
            continue; // nothing to read, whatever the count
        }
        let capacity = element.count.min(1 << 20);
        if is_vertex {
            positions.reserve(capacity);
        }
        let mut values = vec![0.0f64; element.properties.len()];
        for item in 0..element.count {
            let start = body.mark();
            let list = read_item(path, element, item, index_list, body, &mut values)?;
            // Where this element is: its start (binary) or its line (ASCII).
            let mark = if matches!(start, Mark::Line(_)) {
                body.mark()
            } else {
                start
            };
            if let Some([x, y, z]) = xyz {
                let p = Vec3::new(values[x] as f32, values[y] as f32, values[z] as f32);
                if !p.is_finite() {
                    return Err(LoadError::malformed(
                        path,
                        format!("vertex {item} ({mark})"),
                        format!("position {p} is not finite"),
                    ));
                }
                positions.push(p);
                if let Some([a, b, c]) = nxyz {
                    normals.push(Vec3::new(
                        values[a] as f32,
                        values[b] as f32,
                        values[c] as f32,
                    ));
                }
                if let Some([u, v]) = uv {
                    let uv = Vec2::new(values[u] as f32, 1.0 - values[v] as f32);
                    if !uv.is_finite() {
                        return Err(LoadError::malformed(
                            path,
                            format!("vertex {item} ({mark})"),
                            format!("texture coordinates {uv} are not finite"),
                        ));
                    }
                    uvs.push(uv);
                }
            }
            if index_list.is_some() {
                polygons.push((item, mark, list));
            }
        }
    }
    if !seen_vertex {
        return Err(LoadError::malformed(path, "header", "no vertex element"));
    }
    Ok(Elements {
        positions,
        normals,
        uvs,
        polygons,
    })
}

/// The properties illume reads of `element`: positions (required), normals and
/// texture coordinates when it is the vertex element (`is_vertex`), the vertex index
/// list (`vertex_indices`, `vertex_index`, else the first list) when it is the face
/// element (`is_face`).
fn layout(
    path: &Path,
    element: &Element,
    is_vertex: bool,
    is_face: bool,
) -> Result<Layout, LoadError> {
    let find = |names: &[&str]| {
        element
            .properties
            .iter()
            .position(|p| names.contains(&p.name.as_str()) && matches!(p.kind, Kind::Scalar(_)))
    };
    let (xyz, nxyz, uv) = if is_vertex {
        let xyz = [find(&["x"]), find(&["y"]), find(&["z"])];
        let [Some(x), Some(y), Some(z)] = xyz else {
            return Err(LoadError::malformed(
                path,
                "header",
                "vertex element lacks x, y or z",
            ));
        };
        let n = match [find(&["nx"]), find(&["ny"]), find(&["nz"])] {
            [Some(a), Some(b), Some(c)] => Some([a, b, c]),
            _ => None,
        };
        let uv = match [
            find(&["u", "s", "texture_u", "texture_s"]),
            find(&["v", "t", "texture_v", "texture_t"]),
        ] {
            [Some(a), Some(b)] => Some([a, b]),
            _ => None,
        };
        (Some([x, y, z]), n, uv)
    } else {
        (None, None, None)
    };
    let index_list = if is_face {
        let named = element.properties.iter().position(|p| {
            matches!(p.kind, Kind::List { .. })
                && (p.name == "vertex_indices" || p.name == "vertex_index")
        });
        let list = named.or_else(|| {
            element
                .properties
                .iter()
                .position(|p| matches!(p.kind, Kind::List { .. }))
        });
        Some(list.ok_or_else(|| {
            LoadError::malformed(path, "header", "face element has no list property")
        })?)
    } else {
        None
    };
    Ok(Layout {
        xyz,
        nxyz,
        uv,
        index_list,
    })
}

/// Reads item `item` of `element` from `body`: its scalars into `values` (by property),
/// and returns the list at property `index_list` (empty for other elements).
fn read_item(
    path: &Path,
    element: &Element,
    item: usize,
    index_list: Option<usize>,
    body: &mut Body<'_>,
    values: &mut [f64],
) -> Result<Vec<f64>, LoadError> {
    let at = |body: &Body<'_>| format!("{} {item} ({})", excerpt(&element.name), body.place());
    let mut list: Vec<f64> = Vec::new();
    for (k, p) in element.properties.iter().enumerate() {
        match p.kind {
            Kind::Scalar(ty) => {
                let place = at(body);
                values[k] = body.read(ty).map_err(|m| {
                    LoadError::malformed(
                        path,
                        place,
                        format!("property '{}': {m}", excerpt(&p.name)),
                    )
                })?;
            }
            Kind::List { count, item: ty } => {
                let place = at(body);
                let n = body.read(count).map_err(|m| {
                    LoadError::malformed(
                        path,
                        place.clone(),
                        format!("list '{}' count: {m}", excerpt(&p.name)),
                    )
                })?;
                if n < 0.0 {
                    return Err(LoadError::malformed(
                        path,
                        place,
                        format!("list '{}' has negative count {n}", excerpt(&p.name)),
                    ));
                }
                let keep = Some(k) == index_list;
                for _ in 0..n as usize {
                    let place = at(body);
                    let v = body.read(ty).map_err(|m| {
                        LoadError::malformed(
                            path,
                            place,
                            format!("list '{}': {m}", excerpt(&p.name)),
                        )
                    })?;
                    if keep {
                        list.push(v);
                    }
                }
            }
        }
    }
    Ok(list)
}

/// Fans the faces `polygons` into triangles appended to `indices`, each corner checked
/// against the `vertex_count`; returns how many faces had fewer than 3 corners
/// (skipped).
fn triangulate(
    path: &Path,
    vertex_count: usize,
    polygons: &[(usize, Mark, Vec<f64>)],
    indices: &mut Vec<[u32; 3]>,
) -> Result<usize, LoadError> {
    let n = vertex_count;
    let mut skipped = 0usize;
    for (face, mark, corners) in polygons {
        let mut idx = Vec::with_capacity(corners.len());
        for &c in corners {
            if c < 0.0 || c.fract() != 0.0 || c >= n as f64 {
                return Err(LoadError::malformed(
                    path,
                    format!("face {face} ({mark})"),
                    format!("vertex index {c} out of range ({n} vertices)"),
                ));
            }
            idx.push(c as u32);
        }
        if idx.len() < 3 {
            skipped += 1;
            continue;
        }
        for k in 1..idx.len() - 1 {
            indices.push([idx[0], idx[k], idx[k + 1]]);
        }
    }
    Ok(skipped)
}
