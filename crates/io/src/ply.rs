//! PLY read and write (ASCII, binary little- and big-endian) through `ply-rs-bw`, the
//! maintained fork of `ply-rs` (whose last release was in 2020), with the same API.
//!
//! Reading goes through typed element structs (`PropertyAccess` implementations that
//! keep coordinates in fixed fields), not the crate's per-element hash maps, so a
//! million-vertex mesh reads without a map per vertex.

use std::io::{BufRead, Write};
use std::path::Path;
use std::sync::Arc;

use desal_mesh::{Face, TriMesh, Vec3};
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{
    Addable, BeginList, ElementDef, Encoding, Header, Property, PropertyAccess, PropertyAccessResult,
    PropertyDef, PropertyType, ScalarType,
};
use ply_rs_bw::writer::Writer;

use crate::error::IoError;

/// Most extra scalar vertex properties (beyond x, y, z) a read keeps per vertex.
const MAX_EXTRA: usize = 8;

/// How a PLY file is encoded on disk.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PlyEncoding {
    Ascii,
    #[default]
    BinaryLittleEndian,
    BinaryBigEndian,
}

/// What to write besides positions and faces.
#[derive(Debug, Clone, Default)]
pub struct PlyWriteOptions {
    pub encoding: PlyEncoding,
    /// One RGB colour per vertex (`red`, `green`, `blue` as uchar), when given.
    pub colors: Option<Vec<[u8; 3]>>,
    /// Extra float vertex properties, e.g. `("saliency", values)`, one value per vertex.
    pub scalars: Vec<(String, Vec<f32>)>,
    /// Header comments (one line each, no newlines).
    pub comments: Vec<String>,
}

/// A mesh read from a PLY file, with the extra scalar vertex properties it carried.
#[derive(Debug, Clone, Default)]
pub struct PlyMesh {
    pub mesh: TriMesh,
    /// `(name, values)` for every scalar vertex property other than x, y, z (at most
    /// eight), in header order.
    pub scalars: Vec<(String, Vec<f32>)>,
}

/// Reads a PLY mesh (any encoding; a regular file only). Polygons are fan-triangulated.
pub fn read_ply(path: &Path) -> Result<TriMesh, IoError> {
    Ok(read_ply_full(path)?.mesh)
}

/// Reads a PLY mesh and its extra scalar vertex properties (a regular file only).
pub fn read_ply_full(path: &Path) -> Result<PlyMesh, IoError> {
    read_ply_from(path, &crate::file::read_regular_file(path)?)
}

/// Parses PLY content (any encoding); `path` is for messages only.
///
/// Stricter than the PLY crate underneath, because a lenient reader turns a damaged or
/// hand-edited file into a silently wrong mesh:
/// - only `format … 1.0`; no element or property name twice (the crate would merge
///   them and misread every value after);
/// - every element count is checked against the bytes after the header before anything
///   is read (a binary element takes at least the sizes of its scalars and list counts,
///   an ASCII element at least a number and a separator per property);
/// - an ASCII element line must hold exactly the values its properties declare;
/// - the vertex element needs scalar `x`, `y`, `z`, the face element an integer list
///   named `vertex_indices` (or `vertex_index`);
/// - face numbers in messages are the file's own, counted before triangulation.
pub fn read_ply_from(path: &Path, bytes: &[u8]) -> Result<PlyMesh, IoError> {
    let mut reader = Reader::new(std::io::Cursor::new(bytes));
    let header = Parser::<SkipElement>::new()
        .read_header(&mut reader)
        .map_err(|e| IoError::bad_mesh(path, format!("bad PLY header: {e}")))?;
    let header_len = reader.get_ref().position() as usize;
    check_header(path, &header, &bytes[..header_len], bytes.len() - header_len)?;
    let vertex_def = &header.elements["vertex"];
    let extra_names: Vec<String> = vertex_def
        .properties
        .iter()
        .filter(|(name, def)| {
            !matches!(name.as_str(), "x" | "y" | "z") && matches!(def.data_type, PropertyType::Scalar(_))
        })
        .map(|(name, _)| name.clone())
        .take(MAX_EXTRA)
        .collect();

    let (vertices, polygons) = match header.encoding {
        Encoding::Ascii => read_ascii_body(path, &header, bytes, header_len)?,
        _ => read_binary_body(path, &header, &mut reader)?,
    };

    let positions: Vec<Vec3> = vertices.iter().map(|v| Vec3::new(v.p[0], v.p[1], v.p[2])).collect();
    let faces = triangulate(path, &polygons, positions.len(), header.encoding)?;
    let scalars = extra_names
        .into_iter()
        .enumerate()
        .map(|(k, name)| (name, vertices.iter().map(|v| v.extra[k]).collect()))
        .collect();
    let stem = path.display().to_string();
    let mesh = TriMesh::try_new(positions, faces, &stem)
        .map_err(|cause| IoError::InvalidMesh { path: path.to_owned(), cause })?;
    Ok(PlyMesh { mesh, scalars })
}

/// The checks the PLY crate does not make, all before any element is read (see
/// [`read_ply_from`]). `header_bytes` is the raw header, `body_len` the bytes after it.
fn check_header(path: &Path, header: &Header, header_bytes: &[u8], body_len: usize) -> Result<(), IoError> {
    let bad = |reason: String| IoError::bad_mesh(path, reason);
    if (header.version.major, header.version.minor) != (1, 0) {
        return Err(bad(format!(
            "PLY format version {}.{} is not 1.0, the only version there is",
            header.version.major, header.version.minor
        )));
    }
    check_unique_names(path, header_bytes)?;
    let vertex = header.elements.get("vertex").ok_or_else(|| bad("no 'vertex' element".into()))?;
    for axis in ["x", "y", "z"] {
        match vertex.properties.get(axis).map(|p| &p.data_type) {
            Some(PropertyType::Scalar(_)) => {}
            Some(PropertyType::List(..)) => {
                return Err(bad(format!("the vertex property '{axis}' is a list, not a number")));
            }
            None => return Err(bad(format!("the vertex element has no '{axis}' property"))),
        }
    }
    let face = header
        .elements
        .get("face")
        .ok_or_else(|| bad("no 'face' element: a point cloud is not a mesh".into()))?;
    match face.properties.iter().find(|(name, _)| is_index_list(name)) {
        Some((name, def)) => match def.data_type {
            PropertyType::List(_, ScalarType::Float | ScalarType::Double) => {
                return Err(bad(format!("the face list '{name}' holds floats, not vertex indices")));
            }
            PropertyType::Scalar(_) => {
                return Err(bad(format!("the face property '{name}' is a single number, not a list")));
            }
            PropertyType::List(..) => {}
        },
        None => {
            let found: Vec<&str> = face.properties.keys().map(String::as_str).collect();
            return Err(bad(format!(
                "the face element has no 'vertex_indices' list (its properties: {}); desal reads the \
                 vertex index list under the name 'vertex_indices' or 'vertex_index'",
                if found.is_empty() { "none".to_owned() } else { found.join(", ") }
            )));
        }
    }
    // Each element's smallest encoding, summed over the counts, must fit in the body.
    let mut needed: usize = 0;
    for (name, def) in &header.elements {
        if def.properties.is_empty() {
            if def.count > 0 {
                return Err(bad(format!("the element '{name}' has {} entries but no properties", def.count)));
            }
            continue;
        }
        let per_element: usize = match header.encoding {
            Encoding::Ascii => 2 * def.properties.len(),
            _ => def
                .properties
                .values()
                .map(|p| match &p.data_type {
                    PropertyType::Scalar(t) | PropertyType::List(t, _) => scalar_size(t),
                })
                .sum(),
        };
        // An ASCII file may omit the last line's newline.
        let slack = usize::from(header.encoding == Encoding::Ascii);
        needed = def.count.checked_mul(per_element).and_then(|n| n.checked_add(needed)).unwrap_or(usize::MAX);
        if needed > body_len + slack {
            return Err(bad(format!(
                "the header announces {} '{name}' elements of at least {per_element} bytes each, but only {body_len} \
                 bytes follow the header: the element counts are wrong or the file is truncated",
                def.count
            )));
        }
    }
    Ok(())
}

/// Refuses an element named twice, or a property named twice in one element: the PLY
/// crate keeps one of each, and every value after the duplicate would be misread.
fn check_unique_names(path: &Path, header_bytes: &[u8]) -> Result<(), IoError> {
    let text = String::from_utf8_lossy(header_bytes);
    let mut elements: Vec<&str> = Vec::new();
    let mut properties: Vec<&str> = Vec::new();
    for line in text.lines() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("element") => {
                let name = words.next().unwrap_or("");
                if elements.contains(&name) {
                    return Err(IoError::bad_mesh(
                        path,
                        format!("the header declares the element '{name}' twice"),
                    ));
                }
                elements.push(name);
                properties.clear();
            }
            Some("property") => {
                let name = words.next_back().unwrap_or("");
                if properties.contains(&name) {
                    let element = elements.last().copied().unwrap_or("");
                    return Err(IoError::bad_mesh(
                        path,
                        format!("the header declares the property '{name}' of element '{element}' twice"),
                    ));
                }
                properties.push(name);
            }
            _ => {}
        }
    }
    Ok(())
}

fn scalar_size(t: &ScalarType) -> usize {
    match t {
        ScalarType::Char | ScalarType::UChar => 1,
        ScalarType::Short | ScalarType::UShort => 2,
        ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
        ScalarType::Double => 8,
    }
}

/// Reads every element of a binary body through the PLY crate, then refuses trailing data.
fn read_binary_body(
    path: &Path,
    header: &Header,
    reader: &mut Reader<std::io::Cursor<&[u8]>>,
) -> Result<(Vec<VertexIn>, Vec<FaceIn>), IoError> {
    let mut vertices = Vec::new();
    let mut polygons = Vec::new();
    for (name, def) in &header.elements {
        let truncated = |e: ply_rs_bw::parser::ParseError| {
            IoError::bad_mesh(
                path,
                format!("cannot read the {} '{name}' elements (truncated or corrupt?): {e}", def.count),
            )
        };
        match name.as_str() {
            "vertex" => vertices = read_elements(&Parser::new(), reader, def, header).map_err(truncated)?,
            "face" => polygons = read_elements(&Parser::new(), reader, def, header).map_err(truncated)?,
            _ => {
                read_elements(&Parser::<SkipElement>::new(), reader, def, header).map_err(truncated)?;
            }
        }
    }
    // Data past the last element means the header's counts do not describe the file
    // (a concatenation, or counts edited by hand): refused, not silently cut short.
    let cursor = reader.get_ref();
    let rest = cursor.get_ref().len() - cursor.position() as usize;
    if rest > 0 {
        return Err(trailing(path, rest));
    }
    Ok((vertices, polygons))
}

/// Reads the ASCII body of `bytes` (after `header_len` header bytes) one element per
/// line, refusing a line with more or fewer values than its element's properties
/// declare (the PLY crate ignores extra ones).
fn read_ascii_body(
    path: &Path,
    header: &Header,
    bytes: &[u8],
    header_len: usize,
) -> Result<(Vec<VertexIn>, Vec<FaceIn>), IoError> {
    let header_lines = bytes[..header_len].iter().filter(|&&b| b == b'\n').count();
    let text = std::str::from_utf8(&bytes[header_len..])
        .map_err(|e| IoError::NotText { path: path.to_owned(), offset: header_len + e.valid_up_to() })?;
    let mut lines = text.split_inclusive('\n').enumerate().map(|(k, l)| (header_lines + k + 1, l));
    let mut vertices = Vec::new();
    let mut polygons = Vec::new();
    for (name, def) in &header.elements {
        match name.as_str() {
            "vertex" => vertices = read_ascii_elements(path, &Parser::new(), &mut lines, name, def)?,
            "face" => polygons = read_ascii_elements(path, &Parser::new(), &mut lines, name, def)?,
            _ => {
                read_ascii_elements::<SkipElement>(path, &Parser::new(), &mut lines, name, def)?;
            }
        }
    }
    let rest: usize = lines.map(|(_, l)| l.len()).sum();
    if text[text.len() - rest..].bytes().any(|b| !b.is_ascii_whitespace()) {
        return Err(trailing(path, rest));
    }
    Ok((vertices, polygons))
}

fn read_ascii_elements<'a, E: PropertyAccess>(
    path: &Path,
    parser: &Parser<E>,
    lines: &mut impl Iterator<Item = (usize, &'a str)>,
    name: &str,
    def: &ElementDef,
) -> Result<Vec<E>, IoError> {
    // The count was checked against the body's size, so it bounds this allocation.
    let mut out = Vec::with_capacity(def.count);
    for i in 0..def.count {
        let Some((line_no, line)) = lines.next() else {
            return Err(IoError::bad_mesh(
                path,
                format!(
                    "the file ends after {i} of the {} '{name}' elements the header announces",
                    def.count
                ),
            ));
        };
        let bad = |reason: String| IoError::BadLine { path: path.to_owned(), line: line_no, reason };
        let values: Vec<&str> = line.split([' ', '\t', '\r', '\n']).filter(|t| !t.is_empty()).collect();
        let expected =
            ascii_value_count(def, &values).map_err(|reason| bad(format!("{name} {i}: {reason}")))?;
        if values.len() != expected {
            let hint = if i + 1 == def.count && values.len() > expected {
                format!(" (does the header claim more '{name}' elements than the file holds?)")
            } else {
                String::new()
            };
            return Err(bad(format!(
                "{name} {i} has {} values, but the header's '{name}' properties take {expected}{hint}",
                values.len()
            )));
        }
        out.push(parser.read_ascii_element(line, def).map_err(|e| bad(format!("{name} {i}: {e}")))?);
    }
    Ok(out)
}

/// How many values an ASCII line of `def` holds, given its `values` (list lengths come
/// from the line itself). Stops early, with what is needed so far, when `values` run out.
fn ascii_value_count(def: &ElementDef, values: &[&str]) -> Result<usize, String> {
    let mut at: usize = 0;
    for (name, p) in &def.properties {
        match p.data_type {
            PropertyType::Scalar(_) => at += 1,
            PropertyType::List(..) => {
                let Some(t) = values.get(at) else { return Ok(at + 1) };
                let n: usize =
                    t.parse().map_err(|_| format!("the length '{t}' of list '{name}' is not a count"))?;
                at = at.saturating_add(1).saturating_add(n);
            }
        }
        if at > values.len() {
            return Ok(at);
        }
    }
    Ok(at)
}

fn trailing(path: &Path, bytes: usize) -> IoError {
    IoError::bad_mesh(
        path,
        format!(
            "{bytes} byte(s) follow the last element the header announces; the element counts do not match the data"
        ),
    )
}

/// Fan-triangulates the file's polygons, checking each by the file's own face number
/// (before triangulation renumbers them).
fn triangulate(
    path: &Path,
    polygons: &[FaceIn],
    vertex_count: usize,
    encoding: Encoding,
) -> Result<Vec<Face>, IoError> {
    let mut faces: Vec<Face> = Vec::with_capacity(polygons.len());
    for (fi, poly) in polygons.iter().enumerate() {
        let i = poly.indices();
        if i.len() < 3 {
            let hint = if encoding == Encoding::Ascii {
                ""
            } else {
                "; in a binary file this usually means the header's element counts do not match the data \
                 (one vertex or face more or fewer than the file holds)"
            };
            return Err(IoError::bad_mesh(
                path,
                format!("face {fi} has {} vertex indices (a face needs 3 or more){hint}", i.len()),
            ));
        }
        if let Some(&bad) = i.iter().find(|&&i| i < 0) {
            return Err(IoError::bad_mesh(path, format!("face {fi} has a negative vertex index {bad}")));
        }
        if let Some(&bad) = i.iter().find(|&&i| i as u64 >= vertex_count as u64) {
            return Err(IoError::bad_mesh(
                path,
                format!("face {fi} references vertex {bad}, but the file has only {vertex_count} vertices"),
            ));
        }
        for k in 1..i.len() - 1 {
            faces.push([i[0] as u32, i[k] as u32, i[k + 1] as u32]);
        }
    }
    Ok(faces)
}

/// Writes `mesh` (positions as f32, triangles as `uchar int` lists) with the extras in
/// `options`, atomically.
pub fn write_ply(path: &Path, mesh: &TriMesh, options: &PlyWriteOptions) -> Result<(), IoError> {
    let n = mesh.vertex_count();
    if let Some(colors) = &options.colors {
        assert_eq!(colors.len(), n, "one colour per vertex");
    }
    for (name, values) in &options.scalars {
        assert_eq!(values.len(), n, "one '{name}' value per vertex");
        assert!(options.scalars.len() <= MAX_EXTRA, "at most {MAX_EXTRA} scalar properties");
    }
    let header = write_header_def(mesh, options);
    let names: Arc<[String]> = options.scalars.iter().map(|(s, _)| s.clone()).collect();
    let vertices: Vec<VertexOut> = (0..n)
        .map(|v| {
            let p = mesh.positions[v];
            let mut extra = [0f32; MAX_EXTRA];
            for (k, (_, values)) in options.scalars.iter().enumerate() {
                extra[k] = values[v];
            }
            VertexOut {
                p: [p.x as f32, p.y as f32, p.z as f32],
                rgb: options.colors.as_ref().map_or([0; 3], |c| c[v]),
                extra,
                names: names.clone(),
            }
        })
        .collect();
    let faces: Vec<FaceOut> = mesh.faces.iter().map(|f| FaceOut(f.map(|i| i as i32).to_vec())).collect();
    crate::atomic::write_atomic_with(path, |w| {
        Writer::<VertexOut>::new().write_header(w, &header)?;
        Writer::<VertexOut>::new().write_payload_of_element(
            w,
            &vertices,
            &header.elements["vertex"],
            &header,
        )?;
        Writer::<FaceOut>::new().write_payload_of_element(w, &faces, &header.elements["face"], &header)?;
        w.flush()
    })
}

fn write_header_def(mesh: &TriMesh, options: &PlyWriteOptions) -> Header {
    let mut header = Header::new();
    header.encoding = match options.encoding {
        PlyEncoding::Ascii => Encoding::Ascii,
        PlyEncoding::BinaryLittleEndian => Encoding::BinaryLittleEndian,
        PlyEncoding::BinaryBigEndian => Encoding::BinaryBigEndian,
    };
    header.comments = options.comments.clone();
    let mut vertex = ElementDef::new("vertex".to_owned());
    vertex.count = mesh.vertex_count();
    for axis in ["x", "y", "z"] {
        vertex.properties.add(PropertyDef::new(axis.to_owned(), PropertyType::Scalar(ScalarType::Float)));
    }
    if options.colors.is_some() {
        for c in ["red", "green", "blue"] {
            vertex.properties.add(PropertyDef::new(c.to_owned(), PropertyType::Scalar(ScalarType::UChar)));
        }
    }
    for (name, _) in &options.scalars {
        vertex.properties.add(PropertyDef::new(name.clone(), PropertyType::Scalar(ScalarType::Float)));
    }
    header.elements.add(vertex);
    let mut face = ElementDef::new("face".to_owned());
    face.count = mesh.face_count();
    face.properties.add(PropertyDef::new(
        "vertex_indices".to_owned(),
        PropertyType::List(ScalarType::UChar, ScalarType::Int),
    ));
    header.elements.add(face);
    header
}

fn read_elements<E: PropertyAccess, R: BufRead>(
    parser: &Parser<E>,
    reader: &mut Reader<R>,
    def: &ElementDef,
    header: &Header,
) -> ply_rs_bw::parser::Result<Vec<E>> {
    parser.read_payload_for_element(reader, def, header)
}

/// Any numeric property as f64 (lists are not scalars: None).
fn scalar_value(p: &Property) -> Option<f64> {
    Some(match *p {
        Property::Char(v) => v as f64,
        Property::UChar(v) => v as f64,
        Property::Short(v) => v as f64,
        Property::UShort(v) => v as f64,
        Property::Int(v) => v as f64,
        Property::UInt(v) => v as f64,
        Property::Float(v) => v as f64,
        Property::Double(v) => v,
        _ => return None,
    })
}

/// A vertex as read: coordinates in fixed fields, extra scalars in header order.
#[derive(Debug, Clone)]
struct VertexIn {
    p: [f64; 3],
    extra: [f32; MAX_EXTRA],
    next_extra: u8,
}

impl PropertyAccess for VertexIn {
    fn new() -> Self {
        VertexIn { p: [0.0; 3], extra: [0.0; MAX_EXTRA], next_extra: 0 }
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        let Some(value) = scalar_value(&property) else { return PropertyAccessResult::Ignored };
        self.set_value(name, value)
    }

    // The common types get typed setters: no `Property` is built per value.
    fn set_float(&mut self, name: &str, value: f32) -> PropertyAccessResult {
        self.set_value(name, value as f64)
    }

    fn set_double(&mut self, name: &str, value: f64) -> PropertyAccessResult {
        self.set_value(name, value)
    }
}

impl VertexIn {
    fn set_value(&mut self, name: &str, value: f64) -> PropertyAccessResult {
        match name {
            "x" => self.p[0] = value,
            "y" => self.p[1] = value,
            "z" => self.p[2] = value,
            _ => {
                // Extras arrive in header order, matching `extra_names`.
                if (self.next_extra as usize) < MAX_EXTRA {
                    self.extra[self.next_extra as usize] = value as f32;
                    self.next_extra += 1;
                }
            }
        }
        PropertyAccessResult::Set
    }
}

/// A face as read: its vertex index list. `int` and `uint` lists (the usual ones) are
/// filled in place by the parser; other integer types go through the setter.
#[derive(Debug, Clone)]
struct FaceIn {
    int: Vec<i32>,
    uint: Vec<u32>,
    other: Vec<i64>,
}

impl FaceIn {
    fn indices(&self) -> Vec<i64> {
        if !self.int.is_empty() {
            self.int.iter().map(|&i| i64::from(i)).collect()
        } else if !self.uint.is_empty() {
            self.uint.iter().map(|&i| i64::from(i)).collect()
        } else {
            self.other.clone()
        }
    }
}

fn is_index_list(name: &str) -> bool {
    name == "vertex_indices" || name == "vertex_index"
}

impl PropertyAccess for FaceIn {
    fn new() -> Self {
        FaceIn { int: Vec::new(), uint: Vec::new(), other: Vec::new() }
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        if !is_index_list(name) {
            return PropertyAccessResult::Ignored;
        }
        self.other = match property {
            Property::ListChar(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUChar(v) => v.into_iter().map(i64::from).collect(),
            Property::ListShort(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUShort(v) => v.into_iter().map(i64::from).collect(),
            Property::ListInt(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUInt(v) => v.into_iter().map(i64::from).collect(),
            _ => return PropertyAccessResult::UnsupportedType,
        };
        PropertyAccessResult::Set
    }

    fn begin_list_int(&mut self, name: &str, _len: usize) -> BeginList<'_, i32> {
        if is_index_list(name) { BeginList::Fill(&mut self.int) } else { BeginList::UseSetter }
    }

    fn begin_list_uint(&mut self, name: &str, _len: usize) -> BeginList<'_, u32> {
        if is_index_list(name) { BeginList::Fill(&mut self.uint) } else { BeginList::UseSetter }
    }
}

/// Elements desal does not use (edges, materials...): read and dropped.
#[derive(Debug, Clone)]
struct SkipElement;

impl PropertyAccess for SkipElement {
    fn new() -> Self {
        SkipElement
    }
}

/// A vertex as written. `names` is shared by all vertices (one Arc, no copies).
#[derive(Debug, Clone)]
struct VertexOut {
    p: [f32; 3],
    rgb: [u8; 3],
    extra: [f32; MAX_EXTRA],
    names: Arc<[String]>,
}

impl PropertyAccess for VertexOut {
    fn new() -> Self {
        VertexOut { p: [0.0; 3], rgb: [0; 3], extra: [0.0; MAX_EXTRA], names: Arc::from(Vec::new()) }
    }

    fn get_float(&self, name: &str) -> Option<f32> {
        match name {
            "x" => Some(self.p[0]),
            "y" => Some(self.p[1]),
            "z" => Some(self.p[2]),
            other => self.names.iter().position(|n| n == other).map(|k| self.extra[k]),
        }
    }

    fn get_uchar(&self, name: &str) -> Option<u8> {
        match name {
            "red" => Some(self.rgb[0]),
            "green" => Some(self.rgb[1]),
            "blue" => Some(self.rgb[2]),
            _ => None,
        }
    }
}

#[derive(Debug, Clone)]
struct FaceOut(Vec<i32>);

impl PropertyAccess for FaceOut {
    fn new() -> Self {
        FaceOut(Vec::new())
    }

    fn get_list_int(&self, _name: &str) -> Option<&[i32]> {
        Some(&self.0)
    }
}
