//! glTF accessors read by desal itself, each checked against the glTF 2.0 specification
//! before a byte of it is touched, so a hostile file gets an error naming the file and
//! the accessor instead of a panic, an allocation of its choosing or bytes misread.
//!
//! What is checked, in order ([`Accessors::read`]):
//!
//! 1. **Type**: the accessor's type and component type against the specification's table
//!    for what reads it ([`allowed`]; glTF 2.0 §3.7.2.1 for mesh attributes and indices,
//!    §3.7.3.1 for inverse bind matrices, §3.11 for animation samplers), widened by
//!    `KHR_mesh_quantization` when the file declares it. `normalized` must be set where
//!    the table says so and unset where it says not.
//! 2. **Layout**: `count` at least 1; the buffer view within its buffer; `byteStride`
//!    at least the element size; `byteOffset + (count − 1) · stride + element size`
//!    within the view; all in checked arithmetic.
//! 3. **Sparse**: `sparse.count` within `1..=count`, its indices and values within their
//!    views, the indices strictly increasing and below `count` (an index past the count
//!    is refused, not dropped). An accessor without a buffer view is zeros (plus its
//!    sparse values): its count may not exceed the file's real size in bytes, since
//!    every vertex, key or matrix of a valid rig needs at least one byte somewhere.
//!
//! Values are converted to `f32` as the `gltf` crate converts them (`normalized`
//! integers times the reciprocal of the type's maximum, signed ones clamped to −1), so
//! a file the crate read gives the same bits.

use std::fmt;
use std::path::Path;

use gltf::accessor::{DataType, Dimensions};

use crate::RigError;

/// What an accessor is read as: decides which types the specification allows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Semantic {
    Position,
    Normal,
    TexCoord(u32),
    Joints(u32),
    Weights(u32),
    Indices,
    InverseBindMatrices,
    /// Keyframe times.
    AnimationInput,
    Translation,
    Rotation,
    Scale,
    /// Morph target weights (checked, not read: desal carries them unchanged).
    MorphWeights,
    /// An attribute or morph target delta desal does not interpret but carries, element by
    /// element, into a simplified primitive (`TEXCOORD_n`, `COLOR_n`, `TANGENT`,
    /// application attributes, target deltas): any type, checked for layout only, since
    /// its bytes are copied as they are.
    Carried,
}

impl fmt::Display for Semantic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Semantic::Position => write!(f, "POSITION"),
            Semantic::Normal => write!(f, "NORMAL"),
            Semantic::TexCoord(n) => write!(f, "TEXCOORD_{n}"),
            Semantic::Joints(n) => write!(f, "JOINTS_{n}"),
            Semantic::Weights(n) => write!(f, "WEIGHTS_{n}"),
            Semantic::Indices => write!(f, "indices"),
            Semantic::InverseBindMatrices => write!(f, "inverseBindMatrices"),
            Semantic::AnimationInput => write!(f, "keyframe times"),
            Semantic::Translation => write!(f, "translation keyframes"),
            Semantic::Rotation => write!(f, "rotation keyframes"),
            Semantic::Scale => write!(f, "scale keyframes"),
            Semantic::MorphWeights => write!(f, "morph weight keyframes"),
            Semantic::Carried => write!(f, "carried attribute"),
        }
    }
}

/// Whether a component type must be `normalized`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Norm {
    /// `normalized: true` required.
    Yes,
    /// `normalized` absent or false.
    No,
    /// Either (`KHR_mesh_quantization`'s integer positions and UVs).
    Either,
}

/// One allowed component type.
type Component = (DataType, Norm);

const FLOAT: &[Component] = &[(DataType::F32, Norm::No)];
const FLOAT_OR_UNSIGNED_NORMALIZED: &[Component] =
    &[(DataType::F32, Norm::No), (DataType::U8, Norm::Yes), (DataType::U16, Norm::Yes)];
const FLOAT_OR_NORMALIZED: &[Component] = &[
    (DataType::F32, Norm::No),
    (DataType::I8, Norm::Yes),
    (DataType::U8, Norm::Yes),
    (DataType::I16, Norm::Yes),
    (DataType::U16, Norm::Yes),
];
const UNSIGNED_SHORT_OR_BYTE: &[Component] = &[(DataType::U8, Norm::No), (DataType::U16, Norm::No)];
const UNSIGNED_INTEGER: &[Component] =
    &[(DataType::U8, Norm::No), (DataType::U16, Norm::No), (DataType::U32, Norm::No)];
/// `KHR_mesh_quantization`: positions of any 8/16-bit type, normalised or not.
const QUANTIZED_POSITION: &[Component] = &[
    (DataType::F32, Norm::No),
    (DataType::I8, Norm::Either),
    (DataType::U8, Norm::Either),
    (DataType::I16, Norm::Either),
    (DataType::U16, Norm::Either),
];
/// `KHR_mesh_quantization`: normals as normalised signed 8/16-bit.
const QUANTIZED_NORMAL: &[Component] =
    &[(DataType::F32, Norm::No), (DataType::I8, Norm::Yes), (DataType::I16, Norm::Yes)];
/// `KHR_mesh_quantization`: UVs of any 8/16-bit type, normalised or not.
const QUANTIZED_TEXCOORD: &[Component] = QUANTIZED_POSITION;

/// The specification's table: the type and the component types `semantic` may have;
/// `quantized` when the file uses `KHR_mesh_quantization`.
fn allowed(semantic: Semantic, quantized: bool) -> (Dimensions, &'static [Component]) {
    match semantic {
        Semantic::Position if quantized => (Dimensions::Vec3, QUANTIZED_POSITION),
        Semantic::Position => (Dimensions::Vec3, FLOAT),
        Semantic::Normal if quantized => (Dimensions::Vec3, QUANTIZED_NORMAL),
        Semantic::Normal => (Dimensions::Vec3, FLOAT),
        Semantic::TexCoord(_) if quantized => (Dimensions::Vec2, QUANTIZED_TEXCOORD),
        Semantic::TexCoord(_) => (Dimensions::Vec2, FLOAT_OR_UNSIGNED_NORMALIZED),
        Semantic::Joints(_) => (Dimensions::Vec4, UNSIGNED_SHORT_OR_BYTE),
        Semantic::Weights(_) => (Dimensions::Vec4, FLOAT_OR_UNSIGNED_NORMALIZED),
        Semantic::Indices => (Dimensions::Scalar, UNSIGNED_INTEGER),
        Semantic::InverseBindMatrices => (Dimensions::Mat4, FLOAT),
        Semantic::AnimationInput => (Dimensions::Scalar, FLOAT),
        Semantic::Translation | Semantic::Scale => (Dimensions::Vec3, FLOAT),
        Semantic::Rotation => (Dimensions::Vec4, FLOAT_OR_NORMALIZED),
        Semantic::MorphWeights => (Dimensions::Scalar, FLOAT_OR_NORMALIZED),
        Semantic::Carried => unreachable!("carried accessors take any type"),
    }
}

/// The accessors of one file: its buffers' bytes and what the file declares.
pub struct Accessors<'a> {
    pub path: &'a Path,
    /// Every buffer's bytes, by buffer index (at least its declared length).
    pub buffers: &'a [Vec<u8>],
    /// The file uses `KHR_mesh_quantization`.
    pub quantized: bool,
    /// The bytes of the file and its buffers: the most elements an accessor without a
    /// buffer view may count.
    pub real_size: usize,
}

/// A checked accessor's elements as raw components, before conversion.
struct Raw {
    data_type: DataType,
    normalized: bool,
    /// `count · width` components, little-endian as stored, zeros where the accessor
    /// has no buffer view.
    components: Vec<u8>,
}

impl Accessors<'_> {
    /// The accessor's components as `f32`, flattened (`count · width` values);
    /// `used_by` names what reads it (e.g. "mesh 'body' primitive 0").
    pub fn floats(
        &self,
        accessor: &gltf::Accessor<'_>,
        semantic: Semantic,
        used_by: &str,
    ) -> Result<Vec<f32>, RigError> {
        let raw = self.read(accessor, semantic, used_by)?;
        let size = raw.data_type.size();
        let values = raw.components.chunks_exact(size);
        Ok(match (raw.data_type, raw.normalized) {
            (DataType::F32, _) => values.map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect(),
            (DataType::I8, true) => {
                values.map(|c| (c[0] as i8 as f32 * 127.0_f32.recip()).max(-1.0)).collect()
            }
            (DataType::U8, true) => values.map(|c| c[0] as f32 * 255.0_f32.recip()).collect(),
            (DataType::I16, true) => values
                .map(|c| (i16::from_le_bytes([c[0], c[1]]) as f32 * 32767.0_f32.recip()).max(-1.0))
                .collect(),
            (DataType::U16, true) => {
                values.map(|c| u16::from_le_bytes([c[0], c[1]]) as f32 * 65535.0_f32.recip()).collect()
            }
            (DataType::I8, false) => values.map(|c| f32::from(c[0] as i8)).collect(),
            (DataType::U8, false) => values.map(|c| f32::from(c[0])).collect(),
            (DataType::I16, false) => values.map(|c| f32::from(i16::from_le_bytes([c[0], c[1]]))).collect(),
            (DataType::U16, false) => values.map(|c| f32::from(u16::from_le_bytes([c[0], c[1]]))).collect(),
            (DataType::U32, _) => unreachable!("the table allows UNSIGNED_INT for integer semantics only"),
        })
    }

    /// The accessor's components as unsigned integers (`JOINTS_n`, indices), flattened.
    pub fn integers(
        &self,
        accessor: &gltf::Accessor<'_>,
        semantic: Semantic,
        used_by: &str,
    ) -> Result<Vec<u32>, RigError> {
        let raw = self.read(accessor, semantic, used_by)?;
        let size = raw.data_type.size();
        let values = raw.components.chunks_exact(size);
        Ok(match raw.data_type {
            DataType::U8 => values.map(|c| u32::from(c[0])).collect(),
            DataType::U16 => values.map(|c| u32::from(u16::from_le_bytes([c[0], c[1]]))).collect(),
            DataType::U32 => values.map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect(),
            other => unreachable!("the table allows {other:?} for float semantics only"),
        })
    }

    /// Checks the accessor (type, layout, sparse) without keeping its values.
    pub fn check(
        &self,
        accessor: &gltf::Accessor<'_>,
        semantic: Semantic,
        used_by: &str,
    ) -> Result<(), RigError> {
        self.read(accessor, semantic, used_by).map(drop)
    }

    /// The accessor's elements as stored (any type, for [`Semantic::Carried`] and the
    /// attributes desal copies bit for bit), sparse values applied.
    pub fn elements(
        &self,
        accessor: &gltf::Accessor<'_>,
        semantic: Semantic,
        used_by: &str,
    ) -> Result<Elements, RigError> {
        let raw = self.read(accessor, semantic, used_by)?;
        let dimensions = accessor.dimensions();
        Ok(Elements {
            data_type: raw.data_type,
            normalized: raw.normalized,
            dimensions,
            size: dimensions.multiplicity() * raw.data_type.size(),
            bytes: raw.components,
        })
    }

    /// The accessor's type against the specification's table for `semantic`: its
    /// dimensions, or why it does not fit.
    fn check_type(&self, accessor: &gltf::Accessor<'_>, semantic: Semantic) -> Result<Dimensions, String> {
        let (dimensions, components) = allowed(semantic, self.quantized);
        let (data_type, normalized) = (accessor.data_type(), accessor.normalized());
        if accessor.dimensions() != dimensions {
            return Err(format!(
                "has type {}; glTF requires {}",
                type_name(accessor.dimensions()),
                type_name(dimensions)
            ));
        }
        let fits =
            |&(t, n): &Component| t == data_type && (n == Norm::Either || (n == Norm::Yes) == normalized);
        if !components.iter().any(fits) {
            let given = component_name(data_type, normalized);
            let wanted: Vec<String> = components.iter().map(|&(t, n)| allowed_name(t, n)).collect();
            let hint = if self.quantized
                || !matches!(semantic, Semantic::Position | Semantic::Normal | Semantic::TexCoord(_))
            {
                ""
            } else {
                " (quantised attributes need KHR_mesh_quantization in extensionsUsed)"
            };
            return Err(format!("has component type {given}; glTF allows {}{hint}", wanted.join(", ")));
        }
        Ok(dimensions)
    }

    /// The checked accessor's components: its view's elements (or zeros), then its
    /// sparse values written over them.
    fn read(
        &self,
        accessor: &gltf::Accessor<'_>,
        semantic: Semantic,
        used_by: &str,
    ) -> Result<Raw, RigError> {
        let bad = |reason: String| RigError::Accessor {
            path: self.path.to_owned(),
            accessor: accessor.index(),
            semantic: semantic.to_string(),
            used_by: used_by.to_owned(),
            reason,
        };
        let (data_type, normalized) = (accessor.data_type(), accessor.normalized());
        let dimensions = if semantic == Semantic::Carried {
            accessor.dimensions()
        } else {
            self.check_type(accessor, semantic).map_err(bad)?
        };
        let width = dimensions.multiplicity();
        let size = data_type.size();
        let element = width * size;
        let count = accessor.count();
        if count == 0 {
            return Err(bad("has count 0; glTF requires at least 1".into()));
        }
        let total = count.checked_mul(element).ok_or_else(|| bad(format!("count {count} overflows")))?;
        let mut out = match accessor.view() {
            Some(view) => {
                let bytes = self.span(&view, accessor.offset(), count, element, "").map_err(bad)?;
                let mut out = Vec::with_capacity(total);
                for e in 0..count {
                    out.extend_from_slice(&bytes.data[e * bytes.stride..e * bytes.stride + element]);
                }
                out
            }
            None => {
                if count > self.real_size {
                    return Err(bad(format!(
                        "has no buffer view and count {count}, more than the {} bytes of the file and its \
                         buffers",
                        self.real_size
                    )));
                }
                vec![0; total]
            }
        };
        if let Some(sparse) = accessor.sparse() {
            let k = sparse.count();
            if k == 0 || k > count {
                return Err(bad(format!("sparse count {k} is not in 1..={count}")));
            }
            let indices = sparse.indices();
            let index_size = indices.index_type().size();
            let index_bytes = self
                .span(&indices.view(), indices.offset(), k, index_size, "sparse indices ")
                .map_err(bad)?;
            let values = sparse.values();
            let value_bytes =
                self.span(&values.view(), values.offset(), k, element, "sparse values ").map_err(bad)?;
            let mut previous: Option<usize> = None;
            for s in 0..k {
                let at = &index_bytes.data[s * index_bytes.stride..s * index_bytes.stride + index_size];
                let i = match index_size {
                    1 => usize::from(at[0]),
                    2 => usize::from(u16::from_le_bytes([at[0], at[1]])),
                    _ => u32::from_le_bytes([at[0], at[1], at[2], at[3]]) as usize,
                };
                if i >= count {
                    return Err(bad(format!("sparse index {s} is {i}, past the accessor's count {count}")));
                }
                if previous.is_some_and(|p| i <= p) {
                    return Err(bad(format!(
                        "sparse index {s} is {i}; glTF requires strictly increasing indices"
                    )));
                }
                previous = Some(i);
                let value = &value_bytes.data[s * value_bytes.stride..s * value_bytes.stride + element];
                out[i * element..(i + 1) * element].copy_from_slice(value);
            }
        }
        Ok(Raw { data_type, normalized, components: out })
    }

    /// The bytes of `count` elements of `element` bytes at `offset` into `view`, with the
    /// view's stride (or packed); `Err(reason)` when any of it lies outside the view or
    /// the view outside its buffer. `what` prefixes the reasons ("sparse indices ").
    fn span<'s>(
        &'s self,
        view: &gltf::buffer::View<'_>,
        offset: usize,
        count: usize,
        element: usize,
        what: &str,
    ) -> Result<Span<'s>, String> {
        let buffer = view.buffer();
        let v = view.index();
        let Some(data) = self.buffers.get(buffer.index()) else {
            return Err(format!("{what}buffer view {v}: buffer {} was not loaded", buffer.index()));
        };
        let view_end = view.offset().checked_add(view.length());
        let Some(view_bytes) = view_end.and_then(|end| data.get(view.offset()..end)) else {
            return Err(format!(
                "{what}buffer view {v} (offset {}, length {}) lies outside buffer {} ({} bytes)",
                view.offset(),
                view.length(),
                buffer.index(),
                data.len()
            ));
        };
        let stride = view.stride().unwrap_or(element);
        if stride < element {
            return Err(format!(
                "{what}buffer view {v} has byteStride {stride}, smaller than the element's {element} bytes"
            ));
        }
        let end = (count - 1)
            .checked_mul(stride)
            .and_then(|s| s.checked_add(element))
            .and_then(|s| s.checked_add(offset));
        let Some(bytes) = end.and_then(|end| view_bytes.get(offset..end)) else {
            return Err(format!(
                "{what}byteOffset {offset} + {count} elements of {element} bytes every {stride} bytes lie \
                 outside buffer view {v} ({} bytes)",
                view.length()
            ));
        };
        Ok(Span { data: bytes, stride })
    }
}

/// An accessor's elements as stored, tightly packed: element `e` is
/// `bytes[e · size..(e + 1) · size]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Elements {
    pub data_type: DataType,
    pub normalized: bool,
    pub dimensions: Dimensions,
    /// Bytes per element.
    pub size: usize,
    pub bytes: Vec<u8>,
}

impl Elements {
    /// The glTF `type` string (`"VEC3"`).
    pub fn type_name(&self) -> &'static str {
        type_name(self.dimensions)
    }

    /// The glTF `componentType` code.
    pub fn component_code(&self) -> u32 {
        component_code(self.data_type)
    }

    /// Per-component minimum and maximum over elements `picked` (each in range), in the
    /// components' own units, as glTF's `min` and `max` are (integers stay integers).
    pub fn bounds(&self, picked: impl IntoIterator<Item = usize>) -> (Vec<f64>, Vec<f64>) {
        let width = self.dimensions.multiplicity();
        let component = self.data_type.size();
        let mut lo = vec![f64::INFINITY; width];
        let mut hi = vec![f64::NEG_INFINITY; width];
        for e in picked {
            for c in 0..width {
                let at = e * self.size + c * component;
                let b = &self.bytes[at..at + component];
                let x = match self.data_type {
                    DataType::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
                    DataType::I8 => f64::from(b[0] as i8),
                    DataType::U8 => f64::from(b[0]),
                    DataType::I16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
                    DataType::U16 => f64::from(u16::from_le_bytes([b[0], b[1]])),
                    DataType::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
                };
                lo[c] = lo[c].min(x);
                hi[c] = hi[c].max(x);
            }
        }
        (lo, hi)
    }
}

/// The glTF `componentType` code of `data_type`.
pub fn component_code(data_type: DataType) -> u32 {
    match data_type {
        DataType::I8 => 5120,
        DataType::U8 => 5121,
        DataType::I16 => 5122,
        DataType::U16 => 5123,
        DataType::U32 => 5125,
        DataType::F32 => 5126,
    }
}

/// Elements in a buffer: element `e` starts at `e · stride`.
struct Span<'a> {
    data: &'a [u8],
    stride: usize,
}

fn type_name(dimensions: Dimensions) -> &'static str {
    match dimensions {
        Dimensions::Scalar => "SCALAR",
        Dimensions::Vec2 => "VEC2",
        Dimensions::Vec3 => "VEC3",
        Dimensions::Vec4 => "VEC4",
        Dimensions::Mat2 => "MAT2",
        Dimensions::Mat3 => "MAT3",
        Dimensions::Mat4 => "MAT4",
    }
}

fn data_type_name(data_type: DataType) -> &'static str {
    match data_type {
        DataType::I8 => "BYTE",
        DataType::U8 => "UNSIGNED_BYTE",
        DataType::I16 => "SHORT",
        DataType::U16 => "UNSIGNED_SHORT",
        DataType::U32 => "UNSIGNED_INT",
        DataType::F32 => "FLOAT",
    }
}

fn component_name(data_type: DataType, normalized: bool) -> String {
    let name = data_type_name(data_type);
    if normalized { format!("normalized {name}") } else { name.to_owned() }
}

fn allowed_name(data_type: DataType, norm: Norm) -> String {
    let name = data_type_name(data_type);
    match norm {
        Norm::Yes => format!("normalized {name}"),
        Norm::No => name.to_owned(),
        Norm::Either => format!("{name} (normalized or not)"),
    }
}
