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
//! (`strict`): only `format ... 1.0`, no property declared twice in an element, no extra
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

/// Reads the PLY file at `path` (at most [`crate::limits::MAX_PLY_FILE`] bytes). A
/// `.ply.gz` is decompressed only as far as its header's element counts allow (a file
/// declaring 3 vertices followed by gigabytes of zeros stops there). What parsing holds is
/// reserved in `budget` from the declared counts before it is parsed; the mesh stays reserved.
pub fn read_ply(path: &Path, budget: &super::LoadBudget) -> Result<ObjMesh, String> {
    let cap = crate::limits::MAX_PLY_FILE;
    let raw = super::read_capped(path, cap).map_err(|e| format!("cannot open: {e}"))?;
    let file_bytes = raw.len() as u64;
    budget.reserve(file_bytes, "reading it")?;
    let bytes = if path.extension().is_some_and(|e| e == "gz") {
        let out = gunzip_declared(&raw, cap);
        drop(raw);
        budget.release(file_bytes);
        let out = out?;
        budget.reserve(out.len() as u64, "decompressing it")?;
        out
    } else {
        raw
    };
    let held = bytes.len() as u64;
    let result = parse_within(&bytes, budget);
    // The file's bytes are dropped on return; the mesh (reserved by parse_within) stays.
    budget.release(held);
    result
}

/// Checks the header's counts against the data and the budget, then parses `bytes`. What it
/// reserves for parsing is given back; the mesh's share stays reserved when it succeeds.
fn parse_within(bytes: &[u8], budget: &super::LoadBudget) -> Result<ObjMesh, String> {
    let declared = strict::check_header(bytes)?;
    let payload = (bytes.len() as u64).saturating_sub(declared.offset as u64);
    if payload < declared.least() {
        return Err(format!(
            "truncated file: its element counts need at least {} bytes of data, it holds {payload}",
            declared.least()
        ));
    }
    let (parsing, kept) = declared.memory();
    budget.reserve(parsing + kept, "parsing it")?;
    let result = read_bytes(bytes, &declared);
    budget.release(parsing);
    if result.is_err() {
        budget.release(kept);
    }
    result
}

/// Parses the whole file in memory, then the strict checks.
fn read_bytes(bytes: &[u8], payload: &strict::Payload) -> Result<ObjMesh, String> {
    let mut cursor = Cursor::new(bytes);
    let mesh = parse(&mut cursor)?;
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

/// Decompresses a `.ply.gz`: the header (at most 1 MiB), then at most what its element
/// counts declare ([`strict::Payload::bound`]) and `cap` in all; more data is an error.
fn gunzip_declared(gz: &[u8], cap: u64) -> Result<Vec<u8>, String> {
    use std::io::Read;
    let bad = |e: std::io::Error| format!("not valid gzip data: {e}");
    let mut input = flate2::read::MultiGzDecoder::new(gz);
    let mut out = Vec::new();
    let mut chunk = [0u8; 4096];
    const HEADER_CAP: usize = 1 << 20;
    let header_end = loop {
        if let Some(i) = out.windows(10).position(|w| w == b"end_header") {
            if let Some(nl) = out[i..].iter().position(|&b| b == b'\n') {
                break i + nl + 1;
            }
        }
        if out.len() > HEADER_CAP {
            return Err("no end_header in the first 1 MiB".to_string());
        }
        let n = input.read(&mut chunk).map_err(bad)?;
        if n == 0 {
            return Err("no end_header".to_string());
        }
        out.extend_from_slice(&chunk[..n]);
    };
    let bound = strict::check_header(&out[..header_end])?
        .bound()
        .saturating_add(header_end as u64)
        .min(cap);
    let have = out.len() as u64;
    input
        .take((bound + 1).saturating_sub(have))
        .read_to_end(&mut out)
        .map_err(bad)?;
    if out.len() as u64 > bound {
        return Err(format!(
            "decompresses to more than its header declares ({} bytes at most: more data than \
             the element counts, or faces of more than 4 vertices)",
            bound
        ));
    }
    Ok(out)
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
    let normals = ["nx", "ny", "nz"].map(|n| has_prop(def, n));
    if normals.iter().any(|&h| h) && !normals.iter().all(|&h| h) {
        let have: Vec<&str> = ["nx", "ny", "nz"]
            .into_iter()
            .zip(normals)
            .filter_map(|(n, h)| h.then_some(n))
            .collect();
        return Err(format!(
            "the vertex element has {} but not all of nx, ny, nz: normals need the three",
            have.join(", ")
        ));
    }
    if normals.iter().all(|&h| h) {
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
        /// Most bytes one element takes in the file (binary: exact for scalars, lists of the
        /// vertex indices at most 4 long, other lists at most 255; ASCII: 64 bytes a value).
        max_bytes: u64,
        /// Fewest bytes one element takes (lists of vertex indices at least 3 long, others
        /// empty; ASCII: 2 bytes a value).
        min_bytes: u64,
    }

    /// The header's elements and where the payload starts.
    pub struct Payload {
        pub elements: Vec<ElementDecl>,
        pub offset: usize,
        /// `format ascii`: values are text, one separator fewer than values at least.
        ascii: bool,
    }

    impl Payload {
        /// Fewest payload bytes the declared elements can take.
        pub fn least(&self) -> u64 {
            let n = self.elements.iter().fold(0u64, |a, e| {
                a.saturating_add((e.count as u64).saturating_mul(e.min_bytes))
            });
            n.saturating_sub(self.ascii as u64)
        }

        /// Most payload bytes the declared elements can take.
        pub fn bound(&self) -> u64 {
            self.elements.iter().fold(0u64, |a, e| {
                a.saturating_add((e.count as u64).saturating_mul(e.max_bytes))
            })
        }

        /// Bytes parsing holds at its peak beyond the file (the crate's element records:
        /// 128 a vertex or face at most) and bytes the mesh keeps (32 a vertex: position,
        /// normal, uv; 24 a face: up to two triangles), from the declared counts.
        pub fn memory(&self) -> (u64, u64) {
            let count = |n: &str| {
                self.elements
                    .iter()
                    .filter(|e| e.name == n)
                    .map(|e| e.count as u64)
                    .sum::<u64>()
            };
            let all: u64 = self.elements.iter().map(|e| e.count as u64).sum();
            let kept = count("vertex")
                .saturating_mul(32)
                .saturating_add(count("face").saturating_mul(24));
            (all.saturating_mul(128), kept)
        }
    }

    /// Bytes of a PLY scalar type (unknown names: 8, the largest).
    fn type_bytes(t: &str) -> u64 {
        match t {
            "char" | "uchar" | "int8" | "uint8" => 1,
            "short" | "ushort" | "int16" | "uint16" => 2,
            "int" | "uint" | "float" | "int32" | "uint32" | "float32" => 4,
            _ => 8,
        }
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
        let ascii = text
            .lines()
            .any(|l| l.trim_start().starts_with("format ascii"));
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
                    max_bytes: if ascii { 2 } else { 0 },
                    min_bytes: 0,
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
                    let list = words[1] == "list";
                    // (most values, most bytes, fewest values, fewest bytes)
                    let (values, bytes, few, least) = match words.as_slice() {
                        ["property", "list", count, item, _] => {
                            let (lo, hi) = if super::is_index_list(name) {
                                (3, 4)
                            } else {
                                (0, 255)
                            };
                            let (c, i) = (type_bytes(count), type_bytes(item));
                            (1 + hi, c + hi * i, 1 + lo, c + lo * i)
                        }
                        ["property", ty, _] => (1, type_bytes(ty), 1, type_bytes(ty)),
                        _ => (1, 8, 1, 1),
                    };
                    e.max_bytes += if ascii { values * 64 } else { bytes };
                    e.min_bytes += if ascii { few * 2 } else { least };
                    e.props.push((name.to_string(), list));
                }
                _ => {}
            }
        }
        Ok(Payload {
            elements,
            offset,
            ascii,
        })
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
