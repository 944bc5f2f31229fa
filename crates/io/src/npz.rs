//! numpy's `.npz`: a zip of `.npy` arrays, plain arrays only (no pickle), so numpy
//! (`np.load`), Julia, MATLAB or any zip + npy reader loads it; and the layout of
//! `hierarchy.npz` ([`HierarchyArrays`]).
//!
//! Written by hand rather than through a zip crate: the subset is tiny and fixed — stored
//! (uncompressed) entries, as `np.savez` itself writes, npy format 1.0, little-endian
//! `<i4`/`<i8`/`<f8`, C order — and the reader must bound every length by the file's
//! size, which is easiest to see in one short file. CRC-32 comes from `crc32fast`.
//! Limits: no zip64, so under 4 GiB and 65 535 arrays (a hierarchy of SCAPE is ~2 MB).
//!
//! The reader accepts what the writer writes, and `np.savez` files of the same dtypes:
//! stored (or deflated) entries, npy 1.0 or 2.0 headers, C order. It refuses anything else with a
//! message naming the entry. Every write is atomic ([`crate::atomic`]).
//!
//! A second, wider reader serves files desal does not write, such as parametric body
//! models (SMPL's `model.npz`): [`decode_npz_entries`] splits an archive into its entries'
//! raw `.npy` bytes (CRC checked, nothing else parsed; deflated entries of
//! `np.savez_compressed` inflated through `miniz_oxide`, at most 1032 times their stored
//! size, deflate's limit), so an entry can be copied
//! unchanged, and [`decode_npy_any`] parses one of them: booleans, (un)signed integers of
//! 1 to 8 bytes, float32/float64, either byte order, fixed-width unicode (`<U`) and bytes
//! (`S`) strings, C or Fortran order (returned in C order). Object arrays (pickled) are
//! refused by name; their raw bytes stay available.

use std::io::ErrorKind;
use std::path::Path;

use crate::atomic::write_atomic;
use crate::error::IoError;

/// The element type and values of an array, in C order.
#[derive(Debug, Clone, PartialEq)]
pub enum NpyData {
    I32(Vec<i32>),
    I64(Vec<i64>),
    F64(Vec<f64>),
}

impl NpyData {
    fn len(&self) -> usize {
        match self {
            NpyData::I32(v) => v.len(),
            NpyData::I64(v) => v.len(),
            NpyData::F64(v) => v.len(),
        }
    }

    fn descr(&self) -> &'static str {
        match self {
            NpyData::I32(_) => "<i4",
            NpyData::I64(_) => "<i8",
            NpyData::F64(_) => "<f8",
        }
    }
}

/// One array: a shape and `shape.iter().product()` values.
#[derive(Debug, Clone, PartialEq)]
pub struct NpyArray {
    pub shape: Vec<usize>,
    pub data: NpyData,
}

impl NpyArray {
    /// A 1-D array.
    pub fn vector(data: NpyData) -> Self {
        Self { shape: vec![data.len()], data }
    }
}

/// A named array of an npz (the name without `.npy`).
pub type NamedArray = (String, NpyArray);

/// Writes `arrays` as an npz at `path`, atomically. Errors: an array whose shape does
/// not match its length, an archive past the zip limits, or the write itself.
pub fn write_npz(path: &Path, arrays: &[NamedArray]) -> Result<(), IoError> {
    let bytes = encode_npz(arrays).map_err(|reason| invalid(path, reason))?;
    write_atomic(path, &bytes)
}

/// Reads every array of the npz at `path`, in archive order.
/// Anything but a regular file is refused before it is opened.
pub fn read_npz(path: &Path) -> Result<Vec<NamedArray>, IoError> {
    read_npz_from(path, &crate::file::read_regular_file(path)?)
}

/// Parses npz content `bytes`; `path` is for messages only. What [`read_npz`] does after
/// reading the file (the fuzzer's entry point).
pub fn read_npz_from(path: &Path, bytes: &[u8]) -> Result<Vec<NamedArray>, IoError> {
    decode_npz(bytes).map_err(|reason| invalid(path, reason))
}

fn invalid(path: &Path, reason: String) -> IoError {
    IoError::Io { path: path.to_owned(), cause: std::io::Error::new(ErrorKind::InvalidData, reason) }
}

// ---- zip (stored entries only) ----

const LOCAL_SIGNATURE: u32 = 0x0403_4b50;
const CENTRAL_SIGNATURE: u32 = 0x0201_4b50;
const END_SIGNATURE: u32 = 0x0605_4b50;
const LOCAL_HEADER_LEN: usize = 30;
const CENTRAL_HEADER_LEN: usize = 46;
const END_LEN: usize = 22;
/// Version 2.0: the oldest that readers accept for stored entries with directories.
const ZIP_VERSION: u16 = 20;
/// MS-DOS date of 1980-01-01 (the zip epoch): a fixed timestamp keeps the bytes
/// reproducible.
const DOS_DATE: u16 = (1 << 5) | 1;

/// The npz's bytes.
pub fn encode_npz(arrays: &[NamedArray]) -> Result<Vec<u8>, String> {
    let payloads = arrays
        .iter()
        .map(|(name, array)| (name.as_str(), encode_npy(array).map_err(|e| format!("array '{name}': {e}"))));
    encode_archive(payloads, arrays.len())
}

/// The zip archive of `count` named `.npy` payloads (each `Err` is returned as it is).
fn encode_archive<'a>(
    payloads: impl Iterator<Item = (&'a str, Result<Vec<u8>, String>)>,
    count: usize,
) -> Result<Vec<u8>, String> {
    if count > u16::MAX as usize {
        return Err(format!("{count} arrays exceed the zip limit of 65535"));
    }
    let mut out = Vec::new();
    let mut central = Vec::new();
    for (name, payload) in payloads {
        let file_name = format!("{name}.npy");
        let payload = payload?;
        let offset = to_u32(out.len(), "archive")?;
        let size = to_u32(payload.len(), &file_name)?;
        let name_len = u16::try_from(file_name.len()).map_err(|_| format!("name '{name}' is too long"))?;
        let crc = crc32fast::hash(&payload);

        put_u32(&mut out, LOCAL_SIGNATURE);
        for v in [ZIP_VERSION, 0, 0, 0, DOS_DATE] {
            put_u16(&mut out, v); // version, flags, method (stored), time, date
        }
        for v in [crc, size, size] {
            put_u32(&mut out, v);
        }
        put_u16(&mut out, name_len);
        put_u16(&mut out, 0); // extra field length
        out.extend_from_slice(file_name.as_bytes());
        out.extend_from_slice(&payload);

        put_u32(&mut central, CENTRAL_SIGNATURE);
        for v in [ZIP_VERSION, ZIP_VERSION, 0, 0, 0, DOS_DATE] {
            put_u16(&mut central, v); // made by, needed, flags, method, time, date
        }
        for v in [crc, size, size] {
            put_u32(&mut central, v);
        }
        for v in [name_len, 0, 0, 0, 0] {
            put_u16(&mut central, v); // name, extra, comment lengths, disk, internal attrs
        }
        put_u32(&mut central, 0); // external attributes
        put_u32(&mut central, offset);
        central.extend_from_slice(file_name.as_bytes());
    }
    let central_offset = to_u32(out.len(), "archive")?;
    let central_size = to_u32(central.len(), "central directory")?;
    out.extend_from_slice(&central);
    put_u32(&mut out, END_SIGNATURE);
    for v in [0, 0, count as u16, count as u16] {
        put_u16(&mut out, v); // this disk, directory disk, entries here, entries in all
    }
    put_u32(&mut out, central_size);
    put_u32(&mut out, central_offset);
    put_u16(&mut out, 0); // comment length
    to_u32(out.len(), "archive")?;
    Ok(out)
}

/// Decodes an npz from its bytes. Every offset and length read from the file is checked
/// against `bytes.len()` before it is used.
pub fn decode_npz(bytes: &[u8]) -> Result<Vec<NamedArray>, String> {
    decode_npz_entries(bytes)?
        .into_iter()
        .map(|entry| {
            let array = decode_npy(&entry.npy).map_err(|e| format!("entry '{}': {e}", entry.name))?;
            Ok((entry.name, array))
        })
        .collect()
}

/// One entry of an npz as stored: its name without `.npy` and its `.npy` bytes, unparsed
/// (so a writer can copy it unchanged; [`decode_npy_any`] parses it).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NpzEntry {
    pub name: String,
    pub npy: Vec<u8>,
}

/// Reads the entries of the npz at `path`, in archive order, without parsing them.
/// Anything but a regular file is refused before it is opened.
pub fn read_npz_entries(path: &Path) -> Result<Vec<NpzEntry>, IoError> {
    read_npz_entries_from(path, &crate::file::read_regular_file(path)?)
}

/// Splits npz content `bytes` into its entries; `path` is for messages only.
pub fn read_npz_entries_from(path: &Path, bytes: &[u8]) -> Result<Vec<NpzEntry>, IoError> {
    decode_npz_entries(bytes).map_err(|reason| invalid(path, reason))
}

/// The zip layer of [`decode_npz`]: every stored entry's name and bytes, CRC checked.
/// Every offset and length read from the file is checked against `bytes.len()` before it
/// is used, so the entries together hold at most the file's size.
pub fn decode_npz_entries(bytes: &[u8]) -> Result<Vec<NpzEntry>, String> {
    let end = find_end_record(bytes)?;
    let entries = read_u16(bytes, end + 10)? as usize;
    let central_size = read_u32(bytes, end + 12)? as usize;
    let central_offset = read_u32(bytes, end + 16)? as usize;
    if central_offset.checked_add(central_size).is_none_or(|e| e > end) {
        return Err("the central directory lies outside the file".into());
    }
    let mut out = Vec::with_capacity(entries.min(central_size / CENTRAL_HEADER_LEN));
    let mut at = central_offset;
    for _ in 0..entries {
        if read_u32(bytes, at)? != CENTRAL_SIGNATURE {
            return Err(format!("no central directory entry at byte {at}"));
        }
        let method = read_u16(bytes, at + 10)?;
        let crc = read_u32(bytes, at + 16)?;
        let size = read_u32(bytes, at + 20)? as usize;
        let uncompressed = read_u32(bytes, at + 24)? as usize;
        let name_len = read_u16(bytes, at + 28)? as usize;
        let extra_len = read_u16(bytes, at + 30)? as usize;
        let comment_len = read_u16(bytes, at + 32)? as usize;
        let local = read_u32(bytes, at + 42)? as usize;
        let name = slice(bytes, at + CENTRAL_HEADER_LEN, name_len)?;
        let name = std::str::from_utf8(name).map_err(|_| "an entry name is not UTF-8".to_owned())?.to_owned();
        if !(method == 0 && size == uncompressed || method == DEFLATED) {
            return Err(format!(
                "entry '{name}' uses compression method {method}; only stored and deflated entries are read (np.savez, np.savez_compressed)"
            ));
        }
        if read_u32(bytes, local)? != LOCAL_SIGNATURE {
            return Err(format!("entry '{name}': no local header at byte {local}"));
        }
        let local_name = read_u16(bytes, local + 26)? as usize;
        let local_extra = read_u16(bytes, local + 28)? as usize;
        let payload = slice(bytes, local + LOCAL_HEADER_LEN + local_name + local_extra, size)
            .map_err(|e| format!("entry '{name}': {e}"))?;
        let payload = if method == DEFLATED {
            inflate(payload, uncompressed).map_err(|e| format!("entry '{name}': {e}"))?
        } else {
            payload.to_vec()
        };
        if crc32fast::hash(&payload) != crc {
            return Err(format!("entry '{name}': CRC-32 mismatch, the file is corrupt"));
        }
        let stem = name.strip_suffix(".npy").unwrap_or(&name).to_owned();
        out.push(NpzEntry { name: stem, npy: payload });
        at += CENTRAL_HEADER_LEN + name_len + extra_len + comment_len;
    }
    Ok(out)
}

/// Zip's compression method 8, what `np.savez_compressed` writes.
const DEFLATED: u16 = 8;
/// Deflate cannot expand its input more than about 1032 times (258-byte matches coded in
/// 2 bits); a larger announced size is a lie, refused before anything is allocated.
const MAX_INFLATE_RATIO: usize = 1032;

/// A deflated entry's `uncompressed` bytes: announced sizes beyond deflate's ratio are
/// refused, and inflation stops at the announced size, so the output is bounded by
/// 1032 × the entry's stored bytes.
fn inflate(deflated: &[u8], uncompressed: usize) -> Result<Vec<u8>, String> {
    if uncompressed > deflated.len().saturating_mul(MAX_INFLATE_RATIO).saturating_add(64) {
        return Err(format!(
            "announces {uncompressed} bytes from {} deflated ones, more than deflate can expand",
            deflated.len()
        ));
    }
    let out = miniz_oxide::inflate::decompress_to_vec_with_limit(deflated, uncompressed)
        .map_err(|e| format!("the deflated data is corrupt or longer than announced ({:?})", e.status))?;
    if out.len() != uncompressed {
        return Err(format!("inflates to {} bytes, not the {uncompressed} announced", out.len()));
    }
    Ok(out)
}

/// The end-of-central-directory record: the last 22 bytes, or earlier when the archive
/// has a comment (at most 65 535 bytes).
fn find_end_record(bytes: &[u8]) -> Result<usize, String> {
    let last = bytes.len().checked_sub(END_LEN).ok_or("not a zip file: too short")?;
    let first = last.saturating_sub(u16::MAX as usize);
    (first..=last)
        .rev()
        .find(|&at| read_u32(bytes, at) == Ok(END_SIGNATURE))
        .ok_or_else(|| "not a zip file: no end-of-central-directory record".to_owned())
}

// ---- npy ----

const NPY_MAGIC: &[u8] = b"\x93NUMPY";

/// One `.npy` file, format 1.0, header padded so the data starts on a 64-byte boundary
/// (what numpy writes).
fn encode_npy(array: &NpyArray) -> Result<Vec<u8>, String> {
    let count = array.shape.iter().try_fold(1usize, |a, &d| a.checked_mul(d)).ok_or("shape overflows")?;
    if count != array.data.len() {
        return Err(format!(
            "shape {:?} holds {count} values, the data has {}",
            array.shape,
            array.data.len()
        ));
    }
    let mut out = npy_header(array.data.descr(), &array.shape, count * 8)?;
    match &array.data {
        NpyData::I32(v) => v.iter().for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        NpyData::I64(v) => v.iter().for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        NpyData::F64(v) => v.iter().for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
    }
    Ok(out)
}

/// Magic, version 1.0 and the header dict of a C-order array, padded with spaces and a
/// newline so the data starts on a 64-byte boundary; `capacity` is reserved for the data.
fn npy_header(descr: &str, shape: &[usize], capacity: usize) -> Result<Vec<u8>, String> {
    let shape = match shape {
        [one] => format!("({one},)"),
        dims => format!("({})", dims.iter().map(|d| d.to_string()).collect::<Vec<_>>().join(", ")),
    };
    let mut header = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    let unpadded = NPY_MAGIC.len() + 4 + header.len() + 1;
    header.push_str(&" ".repeat((64 - unpadded % 64) % 64));
    header.push('\n');
    let header_len = u16::try_from(header.len()).map_err(|_| "npy header too long".to_owned())?;
    let mut out = Vec::with_capacity(NPY_MAGIC.len() + 4 + header.len() + capacity);
    out.extend_from_slice(NPY_MAGIC);
    out.extend_from_slice(&[1, 0]);
    put_u16(&mut out, header_len);
    out.extend_from_slice(header.as_bytes());
    Ok(out)
}

fn decode_npy(bytes: &[u8]) -> Result<NpyArray, String> {
    let header = parse_npy_header(bytes)?;
    if header.fortran_order {
        return Err("Fortran-order arrays are not supported".into());
    }
    let (shape, count, data) = (header.shape, header.count, &bytes[header.data_offset..]);
    let item = match header.descr.as_str() {
        "<i4" => 4,
        "<i8" | "<f8" => 8,
        other => {
            return Err(format!("dtype '{other}' is not supported (int32, int64, float64 little-endian)"));
        }
    };
    if count.checked_mul(item) != Some(data.len()) {
        return Err(format!(
            "shape {shape:?} needs {count} values of {item} bytes, the entry holds {} bytes",
            data.len()
        ));
    }
    let data = match header.descr.as_str() {
        "<i4" => {
            NpyData::I32(data.chunks_exact(4).map(|c| i32::from_le_bytes(c.try_into().unwrap())).collect())
        }
        "<i8" => {
            NpyData::I64(data.chunks_exact(8).map(|c| i64::from_le_bytes(c.try_into().unwrap())).collect())
        }
        _ => NpyData::F64(data.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().unwrap())).collect()),
    };
    Ok(NpyArray { shape, data })
}

/// What an npy header says: the dtype as written (`'<f8'`), the order, the shape, the
/// element count (checked against overflow) and where the data starts.
struct NpyHeader {
    descr: String,
    fortran_order: bool,
    shape: Vec<usize>,
    count: usize,
    data_offset: usize,
}

fn parse_npy_header(bytes: &[u8]) -> Result<NpyHeader, String> {
    if slice(bytes, 0, NPY_MAGIC.len())? != NPY_MAGIC {
        return Err("not an npy array (bad magic)".into());
    }
    let major = *bytes.get(6).ok_or("truncated npy header")?;
    let (header_len, header_start) = match major {
        1 => (read_u16(bytes, 8)? as usize, 10),
        2 | 3 => (read_u32(bytes, 8)? as usize, 12),
        v => return Err(format!("npy format version {v} is not supported")),
    };
    let header =
        std::str::from_utf8(slice(bytes, header_start, header_len)?).map_err(|_| "npy header is not text")?;
    let descr = header_value(header, "descr")?.trim_matches(|c| c == '\'' || c == '"').to_owned();
    let fortran_order = match header_value(header, "fortran_order")? {
        "False" => false,
        "True" => true,
        other => return Err(format!("npy header's fortran_order is '{other}', not True or False")),
    };
    let shape = parse_shape(header_value(header, "shape")?)?;
    let count = shape.iter().try_fold(1usize, |a, &d| a.checked_mul(d)).ok_or("shape overflows")?;
    Ok(NpyHeader { descr, fortran_order, shape, count, data_offset: header_start + header_len })
}

// ---- npy of any plain dtype (body models and other files desal does not write) ----

/// The values of an array read by [`decode_npy_any`], in C order.
#[derive(Debug, Clone, PartialEq)]
pub enum AnyData {
    Bool(Vec<bool>),
    I8(Vec<i8>),
    U8(Vec<u8>),
    I16(Vec<i16>),
    U16(Vec<u16>),
    I32(Vec<i32>),
    U32(Vec<u32>),
    I64(Vec<i64>),
    U64(Vec<u64>),
    F32(Vec<f32>),
    F64(Vec<f64>),
    /// Fixed-width unicode (`<U{n}`), trailing NULs removed as numpy does.
    Unicode(Vec<String>),
    /// Fixed-width bytes (`|S{n}`), trailing NULs removed as numpy does.
    Bytes(Vec<Vec<u8>>),
}

impl AnyData {
    pub fn len(&self) -> usize {
        match self {
            AnyData::Bool(v) => v.len(),
            AnyData::I8(v) => v.len(),
            AnyData::U8(v) => v.len(),
            AnyData::I16(v) => v.len(),
            AnyData::U16(v) => v.len(),
            AnyData::I32(v) => v.len(),
            AnyData::U32(v) => v.len(),
            AnyData::I64(v) => v.len(),
            AnyData::U64(v) => v.len(),
            AnyData::F32(v) => v.len(),
            AnyData::F64(v) => v.len(),
            AnyData::Unicode(v) => v.len(),
            AnyData::Bytes(v) => v.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// numpy's name of the element type (`float32`, `<U7` as `str`, ...), for messages.
    pub fn type_name(&self) -> &'static str {
        match self {
            AnyData::Bool(_) => "bool",
            AnyData::I8(_) => "int8",
            AnyData::U8(_) => "uint8",
            AnyData::I16(_) => "int16",
            AnyData::U16(_) => "uint16",
            AnyData::I32(_) => "int32",
            AnyData::U32(_) => "uint32",
            AnyData::I64(_) => "int64",
            AnyData::U64(_) => "uint64",
            AnyData::F32(_) => "float32",
            AnyData::F64(_) => "float64",
            AnyData::Unicode(_) => "str",
            AnyData::Bytes(_) => "bytes",
        }
    }

    /// Numeric values as f64 (integers and booleans converted exactly up to 2^53); `None`
    /// for strings.
    pub fn to_f64(&self) -> Option<Vec<f64>> {
        Some(match self {
            AnyData::Bool(v) => v.iter().map(|&x| f64::from(u8::from(x))).collect(),
            AnyData::I8(v) => v.iter().map(|&x| f64::from(x)).collect(),
            AnyData::U8(v) => v.iter().map(|&x| f64::from(x)).collect(),
            AnyData::I16(v) => v.iter().map(|&x| f64::from(x)).collect(),
            AnyData::U16(v) => v.iter().map(|&x| f64::from(x)).collect(),
            AnyData::I32(v) => v.iter().map(|&x| f64::from(x)).collect(),
            AnyData::U32(v) => v.iter().map(|&x| f64::from(x)).collect(),
            AnyData::I64(v) => v.iter().map(|&x| x as f64).collect(),
            AnyData::U64(v) => v.iter().map(|&x| x as f64).collect(),
            AnyData::F32(v) => v.iter().map(|&x| f64::from(x)).collect(),
            AnyData::F64(v) => v.clone(),
            AnyData::Unicode(_) | AnyData::Bytes(_) => return None,
        })
    }

    /// Integer values as i64; `None` for floats and strings, or a uint64 past i64.
    pub fn to_i64(&self) -> Option<Vec<i64>> {
        Some(match self {
            AnyData::Bool(v) => v.iter().map(|&x| i64::from(x)).collect(),
            AnyData::I8(v) => v.iter().map(|&x| i64::from(x)).collect(),
            AnyData::U8(v) => v.iter().map(|&x| i64::from(x)).collect(),
            AnyData::I16(v) => v.iter().map(|&x| i64::from(x)).collect(),
            AnyData::U16(v) => v.iter().map(|&x| i64::from(x)).collect(),
            AnyData::I32(v) => v.iter().map(|&x| i64::from(x)).collect(),
            AnyData::U32(v) => v.iter().map(|&x| i64::from(x)).collect(),
            AnyData::I64(v) => v.clone(),
            AnyData::U64(v) => v.iter().map(|&x| i64::try_from(x).ok()).collect::<Option<_>>()?,
            _ => return None,
        })
    }
}

/// A numeric element type of [`AnyData`]: what a writer keeps when it gives an array back
/// in the type its file stored it in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dtype {
    Bool,
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
}

impl AnyData {
    /// The element type of numeric data; `None` for strings.
    pub fn dtype(&self) -> Option<Dtype> {
        Some(match self {
            AnyData::Bool(_) => Dtype::Bool,
            AnyData::I8(_) => Dtype::I8,
            AnyData::U8(_) => Dtype::U8,
            AnyData::I16(_) => Dtype::I16,
            AnyData::U16(_) => Dtype::U16,
            AnyData::I32(_) => Dtype::I32,
            AnyData::U32(_) => Dtype::U32,
            AnyData::I64(_) => Dtype::I64,
            AnyData::U64(_) => Dtype::U64,
            AnyData::F32(_) => Dtype::F32,
            AnyData::F64(_) => Dtype::F64,
            AnyData::Unicode(_) | AnyData::Bytes(_) => return None,
        })
    }

    /// `values` in `dtype`, as numpy's `astype` casts: floats rounded to nearest for
    /// float32, truncated toward zero (and saturated) for integers, nonzero for bool.
    /// Exact for values the type holds, such as indices read from a file of that type.
    pub fn from_f64(dtype: Dtype, values: &[f64]) -> AnyData {
        macro_rules! cast {
            ($variant:ident, $t:ty) => {
                AnyData::$variant(values.iter().map(|&x| x as $t).collect())
            };
        }
        match dtype {
            Dtype::Bool => AnyData::Bool(values.iter().map(|&x| x != 0.0).collect()),
            Dtype::I8 => cast!(I8, i8),
            Dtype::U8 => cast!(U8, u8),
            Dtype::I16 => cast!(I16, i16),
            Dtype::U16 => cast!(U16, u16),
            Dtype::I32 => cast!(I32, i32),
            Dtype::U32 => cast!(U32, u32),
            Dtype::I64 => cast!(I64, i64),
            Dtype::U64 => cast!(U64, u64),
            Dtype::F32 => cast!(F32, f32),
            Dtype::F64 => AnyData::F64(values.to_vec()),
        }
    }
}

/// An array of any plain dtype: a shape and `shape.iter().product()` values in C order.
#[derive(Debug, Clone, PartialEq)]
pub struct AnyArray {
    pub shape: Vec<usize>,
    pub data: AnyData,
}

/// The element type an npy `descr` names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Element {
    Bool,
    Int { size: usize, signed: bool },
    Float { size: usize },
    Unicode { chars: usize },
    Bytes { len: usize },
}

impl Element {
    fn item_size(self) -> Option<usize> {
        match self {
            Element::Bool => Some(1),
            Element::Int { size, .. } | Element::Float { size } => Some(size),
            Element::Unicode { chars } => chars.checked_mul(4),
            Element::Bytes { len } => Some(len),
        }
    }
}

/// `descr` as (element, big-endian). Refuses object arrays, structured dtypes and sizes
/// numpy's plain kinds do not have.
fn parse_descr(descr: &str) -> Result<(Element, bool), String> {
    let mut chars = descr.chars();
    let (big_endian, rest) = match chars.next() {
        Some('<') => (false, chars.as_str()),
        Some('>') => (true, chars.as_str()),
        Some('|' | '=') => (false, chars.as_str()),
        _ => (false, descr),
    };
    let unsupported = || {
        format!(
            "dtype '{descr}' is not supported (bool, int/uint 8-64, float32/64, unicode or bytes strings)"
        )
    };
    if rest == "O" {
        return Err(format!("dtype '{descr}' is an object array (pickled); it is kept raw, not read"));
    }
    // By character, not byte: a descr is text from the file, any UTF-8.
    let mut kind_and_size = rest.chars();
    let kind = kind_and_size.next().map(String::from).unwrap_or_default();
    let size: usize = kind_and_size.as_str().parse().map_err(|_| unsupported())?;
    let element = match (kind.as_str(), size) {
        ("b", 1) => Element::Bool,
        ("i", 1 | 2 | 4 | 8) => Element::Int { size, signed: true },
        ("u", 1 | 2 | 4 | 8) => Element::Int { size, signed: false },
        ("f", 4 | 8) => Element::Float { size },
        ("U", 1..) => Element::Unicode { chars: size },
        ("S", 1..) => Element::Bytes { len: size },
        _ => return Err(unsupported()),
    };
    Ok((element, big_endian))
}

/// Parses one `.npy` (an [`NpzEntry`]'s bytes) of any plain dtype. The data must be
/// exactly as long as the header's shape and dtype say, so nothing larger than the input
/// is allocated; Fortran-order data is returned in C order.
pub fn decode_npy_any(bytes: &[u8]) -> Result<AnyArray, String> {
    let header = parse_npy_header(bytes)?;
    decode_array_data(&header.descr, header.shape, header.fortran_order, &bytes[header.data_offset..])
}

/// An array from its raw `data` as numpy lays it out: `descr` as in an npy header
/// (`'<f8'`, `'|b1'`, `'<U7'`), `shape`, and the order. `data` must hold exactly the
/// values the shape and dtype say (what a pickled ndarray's state carries, too).
pub fn decode_array_data(
    descr: &str,
    shape: Vec<usize>,
    fortran_order: bool,
    data: &[u8],
) -> Result<AnyArray, String> {
    let count = shape.iter().try_fold(1usize, |a, &d| a.checked_mul(d)).ok_or("shape overflows")?;
    let (element, big) = parse_descr(descr)?;
    let item = element.item_size().ok_or_else(|| format!("dtype '{descr}' overflows"))?;
    if count.checked_mul(item) != Some(data.len()) {
        return Err(format!(
            "shape {shape:?} needs {count} values of {item} bytes, the entry holds {} bytes",
            data.len()
        ));
    }
    macro_rules! numbers {
        ($variant:ident, $t:ty, $n:literal) => {
            AnyData::$variant(
                data.chunks_exact($n)
                    .map(|c| {
                        let c: [u8; $n] = c.try_into().unwrap();
                        if big { <$t>::from_be_bytes(c) } else { <$t>::from_le_bytes(c) }
                    })
                    .collect(),
            )
        };
    }
    let values = match element {
        Element::Bool => AnyData::Bool(data.iter().map(|&b| b != 0).collect()),
        Element::Int { size: 1, signed: true } => numbers!(I8, i8, 1),
        Element::Int { size: 1, signed: false } => numbers!(U8, u8, 1),
        Element::Int { size: 2, signed: true } => numbers!(I16, i16, 2),
        Element::Int { size: 2, signed: false } => numbers!(U16, u16, 2),
        Element::Int { size: 4, signed: true } => numbers!(I32, i32, 4),
        Element::Int { size: 4, signed: false } => numbers!(U32, u32, 4),
        Element::Int { size: 8, signed: true } => numbers!(I64, i64, 8),
        Element::Int { signed: false, .. } => numbers!(U64, u64, 8),
        Element::Int { .. } => numbers!(I64, i64, 8),
        Element::Float { size: 4 } => numbers!(F32, f32, 4),
        Element::Float { .. } => numbers!(F64, f64, 8),
        Element::Unicode { .. } => AnyData::Unicode(
            data.chunks_exact(item)
                .enumerate()
                .map(|(i, c)| utf32_string(c, big).ok_or_else(|| format!("string {i} is not valid unicode")))
                .collect::<Result<_, _>>()?,
        ),
        Element::Bytes { .. } => AnyData::Bytes(
            data.chunks_exact(item)
                .map(|c| c[..c.iter().rposition(|&b| b != 0).map_or(0, |p| p + 1)].to_vec())
                .collect(),
        ),
    };
    let values = if fortran_order { fortran_to_c(values, &shape) } else { values };
    Ok(AnyArray { shape, data: values })
}

/// One fixed-width UTF-32 string without its trailing NULs.
fn utf32_string(bytes: &[u8], big_endian: bool) -> Option<String> {
    let mut out = String::new();
    for c in bytes.chunks_exact(4) {
        let c: [u8; 4] = c.try_into().unwrap();
        let code = if big_endian { u32::from_be_bytes(c) } else { u32::from_le_bytes(c) };
        out.push(char::from_u32(code)?);
    }
    Some(out.trim_end_matches('\0').to_owned())
}

/// Fortran order (first index fastest) to C order (last index fastest).
fn fortran_to_c(values: AnyData, shape: &[usize]) -> AnyData {
    fn permute<T: Clone>(v: Vec<T>, shape: &[usize]) -> Vec<T> {
        if shape.len() < 2 {
            return v;
        }
        // Fortran strides: stride[0] = 1, stride[k] = stride[k-1] * shape[k-1].
        let mut strides = vec![1usize; shape.len()];
        for k in 1..shape.len() {
            strides[k] = strides[k - 1] * shape[k - 1];
        }
        let mut index = vec![0usize; shape.len()];
        let mut out = Vec::with_capacity(v.len());
        for _ in 0..v.len() {
            out.push(v[index.iter().zip(&strides).map(|(i, s)| i * s).sum::<usize>()].clone());
            // Advance the C-order multi-index: the last axis fastest.
            for k in (0..shape.len()).rev() {
                index[k] += 1;
                if index[k] < shape[k] {
                    break;
                }
                index[k] = 0;
            }
        }
        out
    }
    match values {
        AnyData::Bool(v) => AnyData::Bool(permute(v, shape)),
        AnyData::I8(v) => AnyData::I8(permute(v, shape)),
        AnyData::U8(v) => AnyData::U8(permute(v, shape)),
        AnyData::I16(v) => AnyData::I16(permute(v, shape)),
        AnyData::U16(v) => AnyData::U16(permute(v, shape)),
        AnyData::I32(v) => AnyData::I32(permute(v, shape)),
        AnyData::U32(v) => AnyData::U32(permute(v, shape)),
        AnyData::I64(v) => AnyData::I64(permute(v, shape)),
        AnyData::U64(v) => AnyData::U64(permute(v, shape)),
        AnyData::F32(v) => AnyData::F32(permute(v, shape)),
        AnyData::F64(v) => AnyData::F64(permute(v, shape)),
        AnyData::Unicode(v) => AnyData::Unicode(permute(v, shape)),
        AnyData::Bytes(v) => AnyData::Bytes(permute(v, shape)),
    }
}

/// One `.npy` of `array` (format 1.0, little-endian, C order, data 64-byte aligned):
/// what [`decode_npy_any`] reads back, and what numpy loads.
pub fn encode_npy_any(array: &AnyArray) -> Result<Vec<u8>, String> {
    let count = array.shape.iter().try_fold(1usize, |a, &d| a.checked_mul(d)).ok_or("shape overflows")?;
    if count != array.data.len() {
        return Err(format!(
            "shape {:?} holds {count} values, the data has {}",
            array.shape,
            array.data.len()
        ));
    }
    let width = |lens: &mut dyn Iterator<Item = usize>| lens.max().unwrap_or(0).max(1);
    let (descr, item) = match &array.data {
        AnyData::Bool(_) => ("|b1".to_owned(), 1),
        AnyData::I8(_) => ("|i1".to_owned(), 1),
        AnyData::U8(_) => ("|u1".to_owned(), 1),
        AnyData::I16(_) => ("<i2".to_owned(), 2),
        AnyData::U16(_) => ("<u2".to_owned(), 2),
        AnyData::I32(_) => ("<i4".to_owned(), 4),
        AnyData::U32(_) => ("<u4".to_owned(), 4),
        AnyData::I64(_) => ("<i8".to_owned(), 8),
        AnyData::U64(_) => ("<u8".to_owned(), 8),
        AnyData::F32(_) => ("<f4".to_owned(), 4),
        AnyData::F64(_) => ("<f8".to_owned(), 8),
        AnyData::Unicode(v) => {
            let chars = width(&mut v.iter().map(|s| s.chars().count()));
            (format!("<U{chars}"), chars * 4)
        }
        AnyData::Bytes(v) => {
            let len = width(&mut v.iter().map(Vec::len));
            (format!("|S{len}"), len)
        }
    };
    let mut out = npy_header(&descr, &array.shape, count * item)?;
    match &array.data {
        AnyData::Bool(v) => out.extend(v.iter().map(|&b| u8::from(b))),
        AnyData::I8(v) => out.extend(v.iter().map(|&x| x as u8)),
        AnyData::U8(v) => out.extend_from_slice(v),
        AnyData::I16(v) => v.iter().for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        AnyData::U16(v) => v.iter().for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        AnyData::I32(v) => v.iter().for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        AnyData::U32(v) => v.iter().for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        AnyData::I64(v) => v.iter().for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        AnyData::U64(v) => v.iter().for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        AnyData::F32(v) => v.iter().for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        AnyData::F64(v) => v.iter().for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        AnyData::Unicode(v) => {
            for s in v {
                let n = s.chars().count();
                s.chars().for_each(|c| out.extend_from_slice(&u32::from(c).to_le_bytes()));
                out.resize(out.len() + (item / 4 - n) * 4, 0);
            }
        }
        AnyData::Bytes(v) => {
            for b in v {
                out.extend_from_slice(b);
                out.resize(out.len() + item - b.len(), 0);
            }
        }
    }
    Ok(out)
}

/// An npz of `.npy` entries already encoded (by [`encode_npy_any`], or copied from an
/// [`NpzEntry`]): the same stored-entry archive as [`encode_npz`].
pub fn encode_npz_entries(entries: &[NpzEntry]) -> Result<Vec<u8>, String> {
    encode_archive(entries.iter().map(|e| (e.name.as_str(), Ok(e.npy.clone()))), entries.len())
}

/// The text after `'key':` up to the next top-level comma (a tuple's commas are inside
/// parentheses).
fn header_value<'a>(header: &'a str, key: &str) -> Result<&'a str, String> {
    let quoted = [format!("'{key}':"), format!("\"{key}\":")];
    let start = quoted
        .iter()
        .find_map(|k| header.find(k.as_str()).map(|i| i + k.len()))
        .ok_or_else(|| format!("npy header has no '{key}'"))?;
    let rest = &header[start..];
    let mut depth = 0;
    for (i, c) in rest.char_indices() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            ',' | '}' if depth == 0 => return Ok(rest[..i].trim()),
            _ => {}
        }
    }
    Err(format!("npy header value of '{key}' is not terminated"))
}

fn parse_shape(text: &str) -> Result<Vec<usize>, String> {
    let inner = text
        .strip_prefix('(')
        .and_then(|t| t.strip_suffix(')'))
        .ok_or_else(|| format!("npy shape '{text}' is not a tuple"))?;
    inner
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.parse::<usize>().map_err(|_| format!("npy shape '{text}' has a bad dimension '{s}'")))
        .collect()
}

// ---- little-endian helpers, bounds-checked ----

fn slice(bytes: &[u8], at: usize, len: usize) -> Result<&[u8], String> {
    at.checked_add(len)
        .and_then(|end| bytes.get(at..end))
        .ok_or_else(|| format!("{len} bytes at offset {at} run past the end ({} bytes)", bytes.len()))
}

fn read_u16(bytes: &[u8], at: usize) -> Result<u16, String> {
    Ok(u16::from_le_bytes(slice(bytes, at, 2)?.try_into().unwrap()))
}

fn read_u32(bytes: &[u8], at: usize) -> Result<u32, String> {
    Ok(u32::from_le_bytes(slice(bytes, at, 4)?.try_into().unwrap()))
}

fn put_u16(out: &mut Vec<u8>, v: u16) {
    out.extend_from_slice(&v.to_le_bytes());
}

fn put_u32(out: &mut Vec<u8>, v: u32) {
    out.extend_from_slice(&v.to_le_bytes());
}

fn to_u32(n: usize, what: &str) -> Result<u32, String> {
    u32::try_from(n).map_err(|_| format!("{what} exceeds the 4 GiB zip limit (no zip64)"))
}

// ---- hierarchy.npz ----

/// A sparse matrix as COO triplets (scipy's `coo_matrix((data, (row, col)), shape)`).
#[derive(Debug, Clone, PartialEq)]
pub struct CooArrays {
    /// `[rows, cols]`.
    pub shape: [usize; 2],
    pub row: Vec<u32>,
    pub col: Vec<u32>,
    pub data: Vec<f64>,
}

/// The arrays of `hierarchy.npz`, levels `0..=L` (level 0 the input mesh). Keys:
///
/// | key | dtype, shape | meaning |
/// |---|---|---|
/// | `levels` | int64 `(L+1,)` | vertex count of each level, level 0 first |
/// | `F{k}` | int32 `(faces_k, 3)` | faces of level k, in level-k vertex indices |
/// | `A{k}_row/_col/_data/_shape` | int32, int32, float64, int64 `(2,)` | adjacency of level k (COO) |
/// | `D{k}_…` (k < L) | COO, shape `(n_{k+1}, n_k)` | selection: one 1 per row at `map{k+1}` |
/// | `U{k}_…` (k < L) | COO, shape `(n_k, n_{k+1})` | upsampler, rows summing to 1 |
/// | `map{k+1}` (k < L) | int32 `(n_{k+1},)` | each level-(k+1) vertex as a level-k vertex |
/// | `orig{k+1}` (k < L) | int32 `(n_{k+1},)` | each level-(k+1) vertex as a level-0 vertex |
///
/// GraphCMR's conventions: `D{k} · V_k = V_{k+1}` and `U{k} · V_{k+1} ≈ V_k`.
#[derive(Debug, Clone, PartialEq)]
pub struct HierarchyArrays {
    pub levels: Vec<usize>,
    /// `faces[k]`, level k.
    pub faces: Vec<Vec<[u32; 3]>>,
    /// `adjacency[k]`, level k.
    pub adjacency: Vec<CooArrays>,
    /// `down[k]`, `up[k]`, `map[k]`, `orig[k]`: the step k → k+1 (so `map[k]` is `map{k+1}`).
    pub down: Vec<CooArrays>,
    pub up: Vec<CooArrays>,
    pub map: Vec<Vec<u32>>,
    pub orig: Vec<Vec<u32>>,
}

impl HierarchyArrays {
    /// The named arrays in key order: `levels`, then per level `F`, `A`, then per step
    /// `D`, `U`, `map`, `orig`. Errors when the per-level lists have inconsistent lengths
    /// or an index does not fit int32.
    pub fn to_arrays(&self) -> Result<Vec<NamedArray>, String> {
        let l = self.levels.len().checked_sub(1).ok_or("a hierarchy needs at least level 0")?;
        let lists = [self.faces.len(), self.adjacency.len()];
        let steps = [self.down.len(), self.up.len(), self.map.len(), self.orig.len()];
        if lists.iter().any(|&n| n != l + 1) || steps.iter().any(|&n| n != l) {
            return Err(format!(
                "{} levels but per-level lists {lists:?} and per-step lists {steps:?}",
                l + 1
            ));
        }
        let mut out = vec![(
            "levels".to_owned(),
            NpyArray::vector(NpyData::I64(self.levels.iter().map(|&n| n as i64).collect())),
        )];
        for k in 0..=l {
            let faces = int32(self.faces[k].iter().flatten().copied(), &format!("F{k}"))?;
            out.push((format!("F{k}"), NpyArray { shape: vec![self.faces[k].len(), 3], data: faces }));
            push_coo(&mut out, &format!("A{k}"), &self.adjacency[k])?;
        }
        for k in 0..l {
            push_coo(&mut out, &format!("D{k}"), &self.down[k])?;
            push_coo(&mut out, &format!("U{k}"), &self.up[k])?;
            let map = int32(self.map[k].iter().copied(), "map")?;
            out.push((format!("map{}", k + 1), NpyArray::vector(map)));
            let orig = int32(self.orig[k].iter().copied(), "orig")?;
            out.push((format!("orig{}", k + 1), NpyArray::vector(orig)));
        }
        Ok(out)
    }

    /// The inverse of [`HierarchyArrays::to_arrays`]: looks every key up by name, checks
    /// dtypes and shapes.
    pub fn from_arrays(arrays: &[NamedArray]) -> Result<Self, String> {
        let get = |key: &str| {
            arrays.iter().find(|(n, _)| n == key).map(|(_, a)| a).ok_or(format!("no array '{key}'"))
        };
        let levels: Vec<usize> = match &get("levels")?.data {
            NpyData::I64(v) => {
                v.iter().map(|&n| usize::try_from(n).map_err(|_| "negative level".to_owned())).collect()
            }
            _ => Err("'levels' is not int64".to_owned()),
        }?;
        let l = levels.len().checked_sub(1).ok_or("'levels' is empty")?;
        let mut h = HierarchyArrays {
            levels,
            faces: Vec::new(),
            adjacency: Vec::new(),
            down: Vec::new(),
            up: Vec::new(),
            map: Vec::new(),
            orig: Vec::new(),
        };
        for k in 0..=l {
            let f = get(&format!("F{k}"))?;
            let flat = uint32(&f.data, &format!("F{k}"))?;
            if f.shape.len() != 2 || f.shape[1] != 3 {
                return Err(format!("F{k} has shape {:?}, not (faces, 3)", f.shape));
            }
            h.faces.push(flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect());
            h.adjacency.push(read_coo(&get, &format!("A{k}"))?);
        }
        for k in 0..l {
            h.down.push(read_coo(&get, &format!("D{k}"))?);
            h.up.push(read_coo(&get, &format!("U{k}"))?);
            h.map.push(uint32(&get(&format!("map{}", k + 1))?.data, "map")?);
            h.orig.push(uint32(&get(&format!("orig{}", k + 1))?.data, "orig")?);
        }
        Ok(h)
    }
}

/// Writes `hierarchy` to `path` as npz, atomically.
pub fn write_hierarchy_npz(path: &Path, hierarchy: &HierarchyArrays) -> Result<(), IoError> {
    let arrays = hierarchy.to_arrays().map_err(|reason| invalid(path, reason))?;
    write_npz(path, &arrays)
}

/// Reads a `hierarchy.npz` (for tests and `desal inspect`).
pub fn read_hierarchy_npz(path: &Path) -> Result<HierarchyArrays, IoError> {
    let arrays = read_npz(path)?;
    HierarchyArrays::from_arrays(&arrays).map_err(|reason| invalid(path, reason))
}

fn int32(values: impl Iterator<Item = u32>, what: &str) -> Result<NpyData, String> {
    values
        .map(|v| i32::try_from(v).map_err(|_| format!("{what}: index {v} does not fit int32")))
        .collect::<Result<Vec<_>, _>>()
        .map(NpyData::I32)
}

fn uint32(data: &NpyData, what: &str) -> Result<Vec<u32>, String> {
    match data {
        NpyData::I32(v) => {
            v.iter().map(|&x| u32::try_from(x).map_err(|_| format!("{what}: negative index {x}"))).collect()
        }
        _ => Err(format!("{what} is not int32")),
    }
}

fn push_coo(out: &mut Vec<NamedArray>, key: &str, coo: &CooArrays) -> Result<(), String> {
    if coo.row.len() != coo.data.len() || coo.col.len() != coo.data.len() {
        return Err(format!("{key}: row, col and data lengths differ"));
    }
    out.push((format!("{key}_row"), NpyArray::vector(int32(coo.row.iter().copied(), key)?)));
    out.push((format!("{key}_col"), NpyArray::vector(int32(coo.col.iter().copied(), key)?)));
    out.push((format!("{key}_data"), NpyArray::vector(NpyData::F64(coo.data.clone()))));
    let shape = NpyData::I64(coo.shape.iter().map(|&n| n as i64).collect());
    out.push((format!("{key}_shape"), NpyArray::vector(shape)));
    Ok(())
}

fn read_coo<'a>(get: &impl Fn(&str) -> Result<&'a NpyArray, String>, key: &str) -> Result<CooArrays, String> {
    let row = uint32(&get(&format!("{key}_row"))?.data, key)?;
    let col = uint32(&get(&format!("{key}_col"))?.data, key)?;
    let NpyData::F64(data) = &get(&format!("{key}_data"))?.data else {
        return Err(format!("{key}_data is not float64"));
    };
    let NpyData::I64(shape) = &get(&format!("{key}_shape"))?.data else {
        return Err(format!("{key}_shape is not int64"));
    };
    let [rows, cols] = shape[..] else { return Err(format!("{key}_shape does not have 2 entries")) };
    let (rows, cols) = (usize::try_from(rows), usize::try_from(cols));
    let (Ok(rows), Ok(cols)) = (rows, cols) else { return Err(format!("{key}_shape is negative")) };
    if row.len() != data.len() || col.len() != data.len() {
        return Err(format!("{key}: row, col and data lengths differ"));
    }
    if row.iter().any(|&r| r as usize >= rows) || col.iter().any(|&c| c as usize >= cols) {
        return Err(format!("{key}: an index lies outside the shape ({rows}, {cols})"));
    }
    Ok(CooArrays { shape: [rows, cols], row, col, data: data.clone() })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Vec<NamedArray> {
        vec![
            ("a".into(), NpyArray { shape: vec![2, 3], data: NpyData::I32(vec![1, -2, 3, 4, 5, i32::MAX]) }),
            ("b".into(), NpyArray::vector(NpyData::F64(vec![0.1, -0.0, f64::MAX, 1e-300]))),
            ("c".into(), NpyArray::vector(NpyData::I64(vec![]))),
        ]
    }

    /// Write then read gives the same arrays, bit for bit.
    #[test]
    fn round_trip() {
        let bytes = encode_npz(&sample()).unwrap();
        assert_eq!(decode_npz(&bytes).unwrap(), sample());
    }

    /// Every npy header pads the data to a 64-byte boundary, like numpy's.
    #[test]
    fn npy_data_is_64_byte_aligned() {
        for (_, a) in sample() {
            let npy = encode_npy(&a).unwrap();
            let header_len = u16::from_le_bytes([npy[8], npy[9]]) as usize;
            assert_eq!((10 + header_len) % 64, 0);
            assert_eq!(npy[10 + header_len - 1], b'\n');
        }
    }

    /// Any truncation is an error, never a panic or an oversized allocation.
    #[test]
    fn truncated_files_are_refused() {
        let bytes = encode_npz(&sample()).unwrap();
        for len in 0..bytes.len() {
            assert!(decode_npz(&bytes[..len]).is_err(), "truncated to {len} bytes");
        }
    }

    /// A flipped payload byte fails the CRC; a forged huge size is bounded by the file.
    #[test]
    fn corruption_is_refused() {
        let mut bytes = encode_npz(&sample()).unwrap();
        let last_data = bytes.len() - END_LEN - 200;
        bytes[last_data] ^= 1;
        assert!(decode_npz(&bytes).is_err());
        let mut forged = encode_npz(&sample()).unwrap();
        let central =
            u32::from_le_bytes(forged[forged.len() - 6..forged.len() - 2].try_into().unwrap()) as usize;
        forged[central + 20..central + 28].copy_from_slice(&[0xff; 8]);
        let err = decode_npz(&forged).unwrap_err();
        assert!(err.contains("past the end"), "{err}");
    }

    /// A shape that does not match the data is refused at write time.
    #[test]
    fn shape_mismatch_is_refused() {
        let bad = vec![("x".to_owned(), NpyArray { shape: vec![4], data: NpyData::I32(vec![1, 2]) })];
        assert!(encode_npz(&bad).is_err());
    }

    /// The hierarchy layout round-trips through its arrays.
    #[test]
    fn hierarchy_round_trip() {
        let coo = |rows, cols| CooArrays {
            shape: [rows, cols],
            row: vec![0, 1],
            col: vec![1, 0],
            data: vec![0.5, 1.0],
        };
        let h = HierarchyArrays {
            levels: vec![4, 2],
            faces: vec![vec![[0, 1, 2], [0, 2, 3]], vec![[0, 1, 1]]],
            adjacency: vec![coo(4, 4), coo(2, 2)],
            down: vec![coo(2, 4)],
            up: vec![coo(4, 2)],
            map: vec![vec![3, 1]],
            orig: vec![vec![3, 1]],
        };
        let arrays = h.to_arrays().unwrap();
        assert_eq!(HierarchyArrays::from_arrays(&arrays).unwrap(), h);
        let names: Vec<&str> = arrays.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(&names[..4], ["levels", "F0", "A0_row", "A0_col"]);
        assert!(names.contains(&"map1") && names.contains(&"orig1") && names.contains(&"U0_shape"));
    }

    fn any_entry(entries: &[NpzEntry], name: &str) -> AnyArray {
        let entry = entries.iter().find(|e| e.name == name).unwrap_or_else(|| panic!("no entry {name}"));
        decode_npy_any(&entry.npy).unwrap()
    }

    /// A file numpy wrote (`np.savez`, see the test for the call): every dtype, C order
    /// from Fortran-order data, big-endian integers, unicode and bytes scalars. The object
    /// array is refused by name but its bytes are there.
    #[test]
    fn numpy_written_dtypes() {
        let bytes = include_bytes!("../tests/fixtures/numpy_dtypes.npz");
        let entries = decode_npz_entries(bytes).unwrap();
        let f32s = any_entry(&entries, "f32");
        assert_eq!(
            (f32s.shape.as_slice(), f32s.data),
            (&[2, 3][..], AnyData::F32(vec![1.5, -2.25, 3.0, 4.0, 5.0, 6.125]))
        );
        // np.arange(24).reshape(2, 3, 4) stored in Fortran order reads back as 0..24.
        let fortran = any_entry(&entries, "f64_fortran");
        assert_eq!(fortran.shape, [2, 3, 4]);
        assert_eq!(fortran.data, AnyData::F64((0..24).map(f64::from).collect()));
        assert_eq!(any_entry(&entries, "u32").data, AnyData::U32(vec![0, 1, u32::MAX]));
        assert_eq!(any_entry(&entries, "i32_big").data, AnyData::I32(vec![1, -2, 70000]));
        assert_eq!(any_entry(&entries, "u64").data, AnyData::U64(vec![(1 << 63) + 5]));
        assert_eq!(any_entry(&entries, "flag").data, AnyData::Bool(vec![true, false, true]));
        let gender = any_entry(&entries, "gender");
        assert_eq!((gender.shape.len(), gender.data), (0, AnyData::Unicode(vec!["neutral".into()])));
        assert_eq!(any_entry(&entries, "tag").data, AnyData::Bytes(vec![b"lbs".to_vec()]));
        assert_eq!(
            any_entry(&entries, "names").data,
            AnyData::Unicode(vec!["pelvis".into(), "left_hip".into()])
        );
        let object = entries.iter().find(|e| e.name == "obj").unwrap();
        assert!(decode_npy_any(&object.npy).unwrap_err().contains("object array"));
        // The typed reader of hierarchy.npz still refuses what it does not know.
        assert!(decode_npz(bytes).unwrap_err().contains("dtype"));
    }

    /// `np.savez_compressed` (deflated entries) reads like `np.savez`; a forged
    /// uncompressed size past deflate's ratio is refused before inflating.
    #[test]
    fn numpy_compressed() {
        let bytes = include_bytes!("../tests/fixtures/numpy_compressed.npz");
        let entries = decode_npz_entries(bytes).unwrap();
        assert_eq!(any_entry(&entries, "f32").data, AnyData::F32((0..1000).map(|i| i as f32).collect()));
        assert_eq!(any_entry(&entries, "zeros").data, AnyData::F64(vec![0.0; 4096]));
        assert_eq!(any_entry(&entries, "flag").data, AnyData::Bool(vec![true]));
        let mut forged = bytes.to_vec();
        let central =
            u32::from_le_bytes(forged[forged.len() - 6..forged.len() - 2].try_into().unwrap()) as usize;
        forged[central + 24..central + 28].copy_from_slice(&u32::MAX.to_le_bytes());
        let err = decode_npz_entries(&forged).unwrap_err();
        assert!(err.contains("more than deflate can expand"), "{err}");
        for len in 0..bytes.len() {
            assert!(decode_npz_entries(&bytes[..len]).is_err(), "truncated to {len} bytes");
        }
        // Every single-byte change of the deflated file is refused or read, never a panic.
        for at in 0..bytes.len() {
            let mut bad = bytes.to_vec();
            bad[at] ^= 0xa5;
            if let Ok(entries) = decode_npz_entries(&bad) {
                entries.iter().for_each(|e| drop(decode_npy_any(&e.npy)));
            }
        }
    }

    /// Every dtype round-trips through encode_npy_any / decode_npy_any, and copied raw
    /// entries re-archive to the same bytes.
    #[test]
    fn any_dtype_round_trip() {
        let arrays = [
            AnyArray { shape: vec![2], data: AnyData::Bool(vec![true, false]) },
            AnyArray { shape: vec![3], data: AnyData::I8(vec![-1, 0, 127]) },
            AnyArray { shape: vec![1, 2], data: AnyData::U16(vec![7, 65535]) },
            AnyArray { shape: vec![2], data: AnyData::U64(vec![0, u64::MAX]) },
            AnyArray { shape: vec![2, 1], data: AnyData::F32(vec![0.5, -1e30]) },
            AnyArray { shape: vec![], data: AnyData::Unicode(vec!["smpl ✓".into()]) },
            AnyArray { shape: vec![2], data: AnyData::Bytes(vec![b"ab".to_vec(), b"c".to_vec()]) },
        ];
        let entries: Vec<NpzEntry> = arrays
            .iter()
            .enumerate()
            .map(|(i, a)| NpzEntry { name: format!("a{i}"), npy: encode_npy_any(a).unwrap() })
            .collect();
        for (entry, array) in entries.iter().zip(&arrays) {
            assert_eq!(&decode_npy_any(&entry.npy).unwrap(), array);
        }
        let archive = encode_npz_entries(&entries).unwrap();
        assert_eq!(decode_npz_entries(&archive).unwrap(), entries);
    }

    /// Values read as f64 and cast back to the element type they came in are the same
    /// values (what a writer of a model's arrays relies on); strings have no dtype.
    #[test]
    fn numbers_cast_back_to_their_own_dtype() {
        let arrays = [
            AnyData::Bool(vec![true, false]),
            AnyData::I8(vec![-1, 0, 127]),
            AnyData::U8(vec![0, 255]),
            AnyData::I16(vec![-32768, 7]),
            AnyData::U16(vec![7, 65535]),
            AnyData::I32(vec![-1, i32::MAX]),
            AnyData::U32(vec![0, u32::MAX]),
            AnyData::I64(vec![-1, 1 << 52]),
            AnyData::U64(vec![0, 1 << 53]),
            AnyData::F32(vec![0.1, -1e30, f32::MIN_POSITIVE]),
            AnyData::F64(vec![0.1, -1e300]),
        ];
        for data in arrays {
            let dtype = data.dtype().unwrap();
            assert_eq!(AnyData::from_f64(dtype, &data.to_f64().unwrap()), data, "{dtype:?}");
        }
        assert_eq!(AnyData::Unicode(vec!["lbs".into()]).dtype(), None);
    }

    /// A forged shape or descr is refused, never allocated: the data must be exactly as
    /// long as the header says, and zero-width strings are not a dtype.
    #[test]
    fn any_reader_bounds_every_length() {
        let data = [0u8; 12];
        let forged =
            |descr: &str, shape: &[usize]| [npy_header(descr, shape, 0).unwrap(), data.to_vec()].concat();
        assert!(decode_npy_any(&forged("<f4", &[3])).is_ok());
        for (descr, shape) in
            [("<f4", &[1 << 60][..]), ("<f4", &[usize::MAX, 2]), ("<U0", &[3]), ("<f2", &[6])]
        {
            let err = decode_npy_any(&forged(descr, shape)).unwrap_err();
            assert!(
                err.contains("needs") || err.contains("overflows") || err.contains("not supported"),
                "{err}"
            );
        }
        // Found by desal-fuzz's pickle target: a non-ASCII descr once panicked (split at
        // byte 1, inside a character).
        assert!(decode_npy_any(&forged("ÿÿ", &[3])).unwrap_err().contains("not supported"));
        let good = forged("<f4", &[3]);
        for len in 0..good.len() {
            assert!(decode_npy_any(&good[..len]).is_err(), "truncated to {len} bytes");
        }
    }
}
