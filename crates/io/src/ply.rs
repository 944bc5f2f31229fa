//! PLY read and write (ASCII, binary little- and big-endian) through `ply-rs-bw`, the
//! maintained fork of `ply-rs` (whose last release was in 2020), with the same API.
//!
//! Reading goes through typed element structs (`PropertyAccess` implementations that
//! keep coordinates in fixed fields), not the crate's per-element hash maps, so a
//! million-vertex mesh reads without a map per vertex.

use std::fs::File;
use std::io::{BufRead, BufReader, Write};
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

/// Reads a PLY mesh (any encoding). Polygons are fan-triangulated.
pub fn read_ply(path: &Path) -> Result<TriMesh, IoError> {
    Ok(read_ply_full(path)?.mesh)
}

/// Reads a PLY mesh and its extra scalar vertex properties.
pub fn read_ply_full(path: &Path) -> Result<PlyMesh, IoError> {
    let file = File::open(path).map_err(|e| IoError::io(path, e))?;
    let mut reader = Reader::new(BufReader::with_capacity(1 << 20, file));
    let header = Parser::<SkipElement>::new()
        .read_header(&mut reader)
        .map_err(|e| IoError::bad_mesh(path, format!("bad PLY header: {e}")))?;
    let vertex_def =
        header.elements.get("vertex").ok_or_else(|| IoError::bad_mesh(path, "no 'vertex' element"))?;
    for axis in ["x", "y", "z"] {
        if !vertex_def.properties.contains_key(axis) {
            return Err(IoError::bad_mesh(path, format!("the vertex element has no '{axis}' property")));
        }
    }
    let extra_names: Vec<String> = vertex_def
        .properties
        .iter()
        .filter(|(name, def)| {
            !matches!(name.as_str(), "x" | "y" | "z") && matches!(def.data_type, PropertyType::Scalar(_))
        })
        .map(|(name, _)| name.clone())
        .take(MAX_EXTRA)
        .collect();

    let mut vertices: Vec<VertexIn> = Vec::new();
    let mut polygons: Vec<FaceIn> = Vec::new();
    for (name, def) in &header.elements {
        let truncated = |e: ply_rs_bw::parser::ParseError| {
            IoError::bad_mesh(
                path,
                format!("cannot read the {} '{name}' elements (truncated or corrupt?): {e}", def.count),
            )
        };
        match name.as_str() {
            "vertex" => {
                let parser = Parser::<VertexIn>::new();
                vertices = read_elements(&parser, &mut reader, def, &header).map_err(truncated)?;
            }
            "face" => {
                let parser = Parser::<FaceIn>::new();
                polygons = read_elements(&parser, &mut reader, def, &header).map_err(truncated)?;
            }
            _ => {
                let parser = Parser::<SkipElement>::new();
                read_elements(&parser, &mut reader, def, &header).map_err(truncated)?;
            }
        }
    }
    if !header.elements.contains_key("face") {
        return Err(IoError::bad_mesh(path, "no 'face' element: a point cloud is not a mesh"));
    }
    // Data past the last element means the header's counts do not describe the file
    // (a concatenation, or counts edited by hand): refused, not silently cut short.
    let mut rest = Vec::new();
    std::io::Read::read_to_end(reader.get_mut(), &mut rest).map_err(|e| IoError::io(path, e))?;
    let trailing = match header.encoding {
        Encoding::Ascii => rest.iter().filter(|b| !b.is_ascii_whitespace()).count(),
        _ => rest.len(),
    };
    if trailing > 0 {
        return Err(IoError::bad_mesh(
            path,
            format!(
                "{} byte(s) follow the last element the header announces; the element counts do not match the data",
                rest.len()
            ),
        ));
    }

    let positions: Vec<Vec3> = vertices.iter().map(|v| Vec3::new(v.p[0], v.p[1], v.p[2])).collect();
    let mut faces: Vec<Face> = Vec::with_capacity(polygons.len());
    for (fi, poly) in polygons.iter().enumerate() {
        let i = poly.indices();
        if i.len() < 3 {
            return Err(IoError::bad_mesh(path, format!("face {fi} has {} vertices", i.len())));
        }
        if let Some(&bad) = i.iter().find(|&&i| i < 0) {
            return Err(IoError::bad_mesh(path, format!("face {fi} has a negative vertex index {bad}")));
        }
        for k in 1..i.len() - 1 {
            faces.push([i[0] as u32, i[k] as u32, i[k + 1] as u32]);
        }
    }
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
