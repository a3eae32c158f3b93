//! Reads triangle meshes from PLY files (ASCII, binary little- and big-endian) for
//! `Shape "plymesh" "string filename" "mesh.ply"`, through the `ply-rs-bw` crate.
//!
//! What is read:
//! - `element vertex`: `x y z` (float or double), optional normals `nx ny nz`, optional
//!   texture coordinates `u v`, `s t`, `texture_u texture_v` or `texture_s texture_t`;
//!   other vertex properties (colours, ...) are ignored, as pbrt-v4 does.
//! - `element face`: a list property `vertex_indices` (or `vertex_index`) of 3 or 4 indices of
//!   any integer type; quads are split into the triangles (0 1 2) and (0 2 3).
//! - other elements are read past and ignored.
//!
//! Errors (missing file, malformed header, truncated payload, bad numbers, indices out of
//! range, polygons that are neither triangles nor quads) are returned as one-line messages;
//! the caller prefixes the Shape's location and the file name. Stricter than the crate
//! ([`strict`]): only `format ... 1.0`, no property declared twice in an element, no extra
//! values on an ASCII line, and no data after the last element (a face count smaller than the
//! data is an error, not silently dropped faces).

use super::shapes::ObjMesh;
use crate::math::{Vec2, Vec3};
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{ElementDef, Encoding, PropertyAccess, PropertyAccessResult};
use std::io::Cursor;
use std::path::Path;

/// One element of the payload: the fields a vertex or a face may have.
#[derive(Default)]
struct Elem {
    /// x y z nx ny nz u v
    f: [f32; 8],
    /// Face indices as i64, whatever their stored type (negative ones are caught later).
    list: Vec<i64>,
}

/// Slot of a vertex property in `Elem::f`, if it is one we read.
fn slot(name: &str) -> Option<usize> {
    Some(match name {
        "x" => 0,
        "y" => 1,
        "z" => 2,
        "nx" => 3,
        "ny" => 4,
        "nz" => 5,
        "u" | "s" | "texture_u" | "texture_s" => 6,
        "v" | "t" | "texture_v" | "texture_t" => 7,
        _ => return None,
    })
}

fn is_index_list(name: &str) -> bool {
    name == "vertex_indices" || name == "vertex_index"
}

impl Elem {
    fn set_f(&mut self, name: &str, v: f32) -> PropertyAccessResult {
        if let Some(i) = slot(name) {
            self.f[i] = v;
        }
        PropertyAccessResult::Set
    }

    fn set_list<T: Into<i64>>(&mut self, name: &str, v: Vec<T>) -> PropertyAccessResult {
        if is_index_list(name) {
            self.list = v.into_iter().map(Into::into).collect();
        }
        PropertyAccessResult::Set
    }
}

impl PropertyAccess for Elem {
    fn new() -> Self {
        Elem::default()
    }
    fn set_char(&mut self, n: &str, v: i8) -> PropertyAccessResult {
        self.set_f(n, v as f32)
    }
    fn set_uchar(&mut self, n: &str, v: u8) -> PropertyAccessResult {
        self.set_f(n, v as f32)
    }
    fn set_short(&mut self, n: &str, v: i16) -> PropertyAccessResult {
        self.set_f(n, v as f32)
    }
    fn set_ushort(&mut self, n: &str, v: u16) -> PropertyAccessResult {
        self.set_f(n, v as f32)
    }
    fn set_int(&mut self, n: &str, v: i32) -> PropertyAccessResult {
        self.set_f(n, v as f32)
    }
    fn set_uint(&mut self, n: &str, v: u32) -> PropertyAccessResult {
        self.set_f(n, v as f32)
    }
    fn set_float(&mut self, n: &str, v: f32) -> PropertyAccessResult {
        self.set_f(n, v)
    }
    fn set_double(&mut self, n: &str, v: f64) -> PropertyAccessResult {
        self.set_f(n, v as f32)
    }
    fn set_list_char(&mut self, n: &str, v: Vec<i8>) -> PropertyAccessResult {
        self.set_list(n, v)
    }
    fn set_list_uchar(&mut self, n: &str, v: Vec<u8>) -> PropertyAccessResult {
        self.set_list(n, v)
    }
    fn set_list_short(&mut self, n: &str, v: Vec<i16>) -> PropertyAccessResult {
        self.set_list(n, v)
    }
    fn set_list_ushort(&mut self, n: &str, v: Vec<u16>) -> PropertyAccessResult {
        self.set_list(n, v)
    }
    fn set_list_int(&mut self, n: &str, v: Vec<i32>) -> PropertyAccessResult {
        self.set_list(n, v)
    }
    fn set_list_uint(&mut self, n: &str, v: Vec<u32>) -> PropertyAccessResult {
        self.set_list(n, v)
    }
    fn set_list_float(&mut self, _n: &str, _v: Vec<f32>) -> PropertyAccessResult {
        PropertyAccessResult::Set
    }
    fn set_list_double(&mut self, _n: &str, _v: Vec<f64>) -> PropertyAccessResult {
        PropertyAccessResult::Set
    }
}

/// Makes a crate error one line: newlines and tabs folded into single spaces.
/// Only the first sentence group is kept: the crate appends the nested parser's error after
/// "Error:", which repeats the line or lists grammar alternatives.
fn one_line(s: &str) -> String {
    let folded = s.split_whitespace().collect::<Vec<_>>().join(" ");
    match folded.find(" Error: ") {
        Some(i) => folded[..i].to_string(),
        None => folded,
    }
}

/// Reads the PLY file at `path` (at most [`crate::resources::MAX_PLY_FILE`] bytes, also after
/// decompressing a `.ply.gz`).
pub fn read_ply(path: &Path) -> Result<ObjMesh, String> {
    let bytes = super::read_input(path, crate::resources::MAX_PLY_FILE)
        .map_err(|e| format!("cannot open: {e}"))?;
    let mut cursor = Cursor::new(&bytes[..]);
    let mesh = parse(&mut cursor)?;
    let payload = strict::check_header(&bytes)?;
    if bytes.starts_with(b"ply\nformat ascii") || bytes.starts_with(b"ply\r\nformat ascii") {
        strict::check_ascii(&bytes[payload.offset..], &payload.elements)?;
    } else if (cursor.position() as usize) < bytes.len() {
        return Err(format!(
            "{} bytes after the last element: the header's element counts are smaller than the data",
            bytes.len() - cursor.position() as usize
        ));
    }
    Ok(mesh)
}

/// Parses the header and payload through `ply-rs-bw`.
fn parse(input: &mut Cursor<&[u8]>) -> Result<ObjMesh, String> {
    let mut reader = Reader::new(input);
    let parser = Parser::<Elem>::new();
    let header = parser
        .read_header(&mut reader)
        .map_err(|e| format!("malformed header: {}", one_line(&e.to_string())))?;
    let mut mesh = ObjMesh::default();
    let mut saw_vertex = false;
    let mut saw_face = false;
    for (name, def) in &header.elements {
        let elems = parser
            .read_payload_for_element(&mut reader, def, &header)
            .map_err(|e| payload_error(name, &e, header.encoding == Encoding::Ascii))?;
        match name.as_str() {
            "vertex" => {
                vertices(def, &elems, &mut mesh)?;
                saw_vertex = true;
            }
            "face" => {
                faces(def, &elems, &mut mesh)?;
                saw_face = true;
            }
            _ => {}
        }
    }
    if !saw_vertex {
        return Err("no \"vertex\" element".to_string());
    }
    if !saw_face {
        return Err("no \"face\" element".to_string());
    }
    check_indices(&mesh)?;
    Ok(mesh)
}

/// Describes a payload error, naming truncation as such.
/// Binary files have no lines, so the crate's "Line N:" prefix is dropped for them.
fn payload_error(element: &str, e: &ply_rs_bw::parser::ParseError, ascii: bool) -> String {
    let what = if e.kind() == std::io::ErrorKind::UnexpectedEof {
        "truncated file"
    } else {
        "malformed data"
    };
    let mut msg = one_line(&e.to_string());
    if !ascii && msg.starts_with("Line ") {
        if let Some(i) = msg.find(": ") {
            msg = msg[i + 2..].to_string();
        }
    }
    format!("{what} in element \"{element}\": {msg}")
}

/// Whether `def` has a property called `name`.
fn has_prop(def: &ElementDef, name: &str) -> bool {
    def.properties.contains_key(name)
}

/// Copies the vertex element into `mesh` (positions, and normals / uvs when all present).
fn vertices(def: &ElementDef, elems: &[Elem], mesh: &mut ObjMesh) -> Result<(), String> {
    if !["x", "y", "z"].iter().all(|n| has_prop(def, n)) {
        return Err("the vertex element lacks x, y or z".to_string());
    }
    mesh.positions = elems
        .iter()
        .map(|e| Vec3::new(e.f[0], e.f[1], e.f[2]))
        .collect();
    if let Some(bad) = mesh.positions.iter().position(|p| !p.is_finite()) {
        return Err(format!("vertex {bad} is not finite"));
    }
    if ["nx", "ny", "nz"].iter().all(|n| has_prop(def, n)) {
        mesh.normals = Some(
            elems
                .iter()
                .map(|e| Vec3::new(e.f[3], e.f[4], e.f[5]))
                .collect(),
        );
    }
    let uv_names = [
        ("u", "v"),
        ("s", "t"),
        ("texture_u", "texture_v"),
        ("texture_s", "texture_t"),
    ];
    if uv_names
        .iter()
        .any(|(u, v)| has_prop(def, u) && has_prop(def, v))
    {
        mesh.uvs = Some(elems.iter().map(|e| Vec2::new(e.f[6], e.f[7])).collect());
    }
    Ok(())
}

/// Triangulates the face element into `mesh.indices`.
fn faces(def: &ElementDef, elems: &[Elem], mesh: &mut ObjMesh) -> Result<(), String> {
    if !def.properties.keys().any(|k| is_index_list(k)) {
        return Err("the face element has no vertex_indices list".to_string());
    }
    mesh.indices.reserve(elems.len());
    for (f, e) in elems.iter().enumerate() {
        let idx = |i: usize| -> Result<u32, String> {
            u32::try_from(e.list[i]).map_err(|_| format!("face {f}: negative index {}", e.list[i]))
        };
        match e.list.len() {
            3 => mesh.indices.push([idx(0)?, idx(1)?, idx(2)?]),
            4 => {
                let q = [idx(0)?, idx(1)?, idx(2)?, idx(3)?];
                mesh.indices.push([q[0], q[1], q[2]]);
                mesh.indices.push([q[0], q[2], q[3]]);
            }
            n => {
                return Err(format!(
                    "face {f} has {n} vertices (only triangles and quads)"
                ))
            }
        }
    }
    Ok(())
}

/// Every index must name a vertex.
fn check_indices(mesh: &ObjMesh) -> Result<(), String> {
    let n = mesh.positions.len();
    for (t, tri) in mesh.indices.iter().enumerate() {
        if let Some(&bad) = tri.iter().find(|&&i| i as usize >= n) {
            return Err(format!(
                "vertex index {bad} out of range (there are {n} vertices) in triangle {t}"
            ));
        }
    }
    Ok(())
}

/// Checks the crate lets pass: the header's version and duplicate properties, extra values on
/// ASCII lines, and data beyond the elements the header declares.
mod strict {
    /// An element of the header: name, count and its properties (name, is a list).
    pub struct ElementDecl {
        name: String,
        count: usize,
        props: Vec<(String, bool)>,
    }

    /// The header's elements and where the payload starts.
    pub struct Payload {
        pub elements: Vec<ElementDecl>,
        pub offset: usize,
    }

    /// Reads the (already validated by the crate) header again: version 1.0 only, and no
    /// property declared twice in one element.
    pub fn check_header(bytes: &[u8]) -> Result<Payload, String> {
        let end = bytes
            .windows(10)
            .position(|w| w == b"end_header")
            .ok_or("no end_header")?;
        let offset = bytes[end..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |i| end + i + 1);
        let text = String::from_utf8_lossy(&bytes[..end]);
        let mut elements: Vec<ElementDecl> = Vec::new();
        for line in text.lines() {
            let words: Vec<&str> = line.split_whitespace().collect();
            match words.as_slice() {
                ["format", _, version] if *version != "1.0" => {
                    return Err(format!(
                        "unsupported PLY version {} (only 1.0)",
                        crate::scene::clip_for_message(version, crate::scene::MAX_TOKEN)
                    ))
                }
                ["element", name, count] => elements.push(ElementDecl {
                    name: name.to_string(),
                    count: count.parse().unwrap_or(0),
                    props: Vec::new(),
                }),
                ["property", .., name] => {
                    let Some(e) = elements.last_mut() else {
                        continue;
                    };
                    if e.props.iter().any(|(n, _)| n == name) {
                        return Err(format!(
                            "element \"{}\" declares property \"{}\" twice",
                            e.name,
                            crate::scene::clip_for_message(name, crate::scene::MAX_TOKEN)
                        ));
                    }
                    e.props.push((name.to_string(), words[1] == "list"));
                }
                _ => {}
            }
        }
        Ok(Payload { elements, offset })
    }

    /// Every ASCII payload line holds exactly the values its element declares, and nothing
    /// follows the last element.
    pub fn check_ascii(payload: &[u8], elements: &[ElementDecl]) -> Result<(), String> {
        let text = String::from_utf8_lossy(payload);
        let mut lines = text.lines().filter(|l| !l.trim().is_empty());
        for e in elements {
            for i in 0..e.count {
                let Some(line) = lines.next() else {
                    return Ok(()); // the crate reported truncation already
                };
                let values: Vec<&str> = line.split_whitespace().collect();
                let want = expected_values(&e.props, &values);
                if values.len() > want {
                    return Err(format!(
                        "element \"{}\" {i}: {} values on its line, the header declares {want}",
                        e.name,
                        values.len()
                    ));
                }
            }
        }
        match lines.count() {
            0 => Ok(()),
            n => Err(format!(
                "{n} lines after the last element: the header's element counts are smaller than the data"
            )),
        }
    }

    /// How many values a line with properties `props` holds (a list's length is its first
    /// value); unreadable lengths count as 0 (the crate reports them).
    fn expected_values(props: &[(String, bool)], values: &[&str]) -> usize {
        let mut at = 0usize;
        for (_, list) in props {
            if *list {
                let n: usize = values.get(at).and_then(|v| v.parse().ok()).unwrap_or(0);
                at = at.saturating_add(1).saturating_add(n);
            } else {
                at += 1;
            }
        }
        at
    }
}
