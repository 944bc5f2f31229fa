//! The versioned artifact envelope shared by every binary artifact desal writes.
//!
//! Layout (all integers little-endian):
//!
//! | bytes  | field                                                     |
//! |--------|-----------------------------------------------------------|
//! | 0..8   | magic `DESALART`                                          |
//! | 8..10  | artifact kind (`ArtifactKind` code)                       |
//! | 10..12 | format version of that kind                               |
//! | 12..16 | reserved, must be zero                                    |
//! | 16..24 | payload length in bytes                                   |
//! | 24..56 | BLAKE3 hash of the payload (checksum and content hash)    |
//! | 56..   | payload: bincode of `(Producer, body)`                    |
//!
//! Readers check, in order: magic ("not ours"), kind ("wrong kind"), version ("newer" /
//! "older"), reserved bytes, length ("truncated"), checksum ("corrupt"), then decode. The
//! payload hash doubles as the artifact's content hash, which the cache uses as the
//! identity of a stage's input. The producer carries no timings or paths, so the same
//! inputs and parameters give byte-identical artifacts.

mod types;

use std::fmt;
use std::path::Path;

use serde::{Deserialize, Serialize, de::DeserializeOwned};

pub use types::*;

use crate::codec;
use crate::error::IoError;

pub mod layout;
pub use layout::{HEADER_LEN, MAGIC};

/// What an artifact holds. Codes are frozen: never reuse or renumber one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ArtifactKind {
    /// A validated, registered pose set (ingest).
    PoseSet = 1,
    /// Per-vertex part labels validated against a pose set (ingest).
    Labels = 2,
    /// Per-pose, per-part rigid transforms and residuals (stage 1).
    Fit = 3,
    /// Per-vertex saliency and stage-3 weights (stage 2).
    Saliency = 4,
    /// A simplified template (stage 3).
    Simplified = 5,
    /// The simplified-to-original vertex map (stage 4).
    Map = 6,
    /// One level of a hierarchy: selection, upsampler, coarse faces (stage `hierarchy`).
    HierarchyLevel = 7,
    /// A deformation model's own error at full resolution (`desal eval`).
    Floor = 8,
}

impl ArtifactKind {
    pub const ALL: [ArtifactKind; 8] = [
        ArtifactKind::PoseSet,
        ArtifactKind::Labels,
        ArtifactKind::Fit,
        ArtifactKind::Saliency,
        ArtifactKind::Simplified,
        ArtifactKind::Map,
        ArtifactKind::HierarchyLevel,
        ArtifactKind::Floor,
    ];

    pub fn name(self) -> &'static str {
        match self {
            ArtifactKind::PoseSet => "pose-set",
            ArtifactKind::Labels => "labels",
            ArtifactKind::Fit => "fit",
            ArtifactKind::Saliency => "saliency",
            ArtifactKind::Simplified => "simplified",
            ArtifactKind::Map => "map",
            ArtifactKind::HierarchyLevel => "hierarchy-level",
            ArtifactKind::Floor => "floor",
        }
    }

    /// The format version this build writes and reads for this kind.
    /// Pose set 2: one group id per pose (`PoseSetV2::groups`, empty for none).
    pub fn current_version(self) -> u16 {
        match self {
            ArtifactKind::PoseSet => 2,
            _ => 1,
        }
    }

    /// The oldest format version this build still reads for this kind (an older body is
    /// decoded by [`ArtifactBody::decode_older`] and brought to the current layout).
    pub fn oldest_readable_version(self) -> u16 {
        match self {
            ArtifactKind::PoseSet => 1,
            _ => self.current_version(),
        }
    }

    fn from_code(code: u16) -> Option<Self> {
        Self::ALL.into_iter().find(|k| *k as u16 == code)
    }
}

impl fmt::Display for ArtifactKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A BLAKE3 content hash, shown and serialised as 64 hex digits.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ContentHash(pub [u8; 32]);

impl ContentHash {
    pub fn of(bytes: &[u8]) -> Self {
        ContentHash(*blake3::hash(bytes).as_bytes())
    }

    pub fn to_hex(&self) -> String {
        self.0.iter().map(|b| format!("{b:02x}")).collect()
    }

    pub fn from_hex(text: &str) -> Option<Self> {
        if text.len() != 64 {
            return None;
        }
        let mut out = [0u8; 32];
        for (k, slot) in out.iter_mut().enumerate() {
            *slot = u8::from_str_radix(text.get(2 * k..2 * k + 2)?, 16).ok()?;
        }
        Some(ContentHash(out))
    }

    /// The first 12 hex digits, for display.
    pub fn short(&self) -> String {
        self.to_hex()[..12].to_owned()
    }
}

impl fmt::Debug for ContentHash {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "ContentHash({})", self.short())
    }
}

impl fmt::Display for ContentHash {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.to_hex())
    }
}

impl Serialize for ContentHash {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.to_hex())
    }
}

impl<'de> Deserialize<'de> for ContentHash {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let text = String::deserialize(d)?;
        ContentHash::from_hex(&text).ok_or_else(|| serde::de::Error::custom("expected 64 hex digits"))
    }
}

/// Who made an artifact and from what. No timings and no absolute paths: two runs with
/// the same inputs and parameters write the same producer.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Producer {
    /// Stage id, e.g. `fit`.
    pub stage: String,
    /// Version of the stage's algorithm; bumped when its output changes for the same input.
    pub stage_version: u32,
    /// desal release that wrote it.
    pub tool_version: String,
    /// The stage parameters as canonical JSON (sorted keys, no whitespace).
    pub parameters: String,
    /// Inputs by role, with their content hashes.
    pub inputs: Vec<InputRef>,
}

/// One input of a stage run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InputRef {
    /// What the input is to the stage, e.g. `poses`, `labels`, `pose:mesh003`.
    pub role: String,
    /// Content hash of the input (file bytes for source files, payload hash for artifacts).
    pub hash: ContentHash,
    /// A human hint (file name); never part of any cache key.
    pub hint: String,
}

/// A payload type with its artifact kind.
pub trait ArtifactBody: Serialize + DeserializeOwned {
    const KIND: ArtifactKind;

    /// Checks what the byte format cannot: that the body agrees with itself (array
    /// lengths match the counts they are indexed by, every index is in range), so that
    /// code using a decoded body may index it without checks. Returns the first
    /// inconsistency, naming the field and the offending entry. Run by every decode.
    fn validate(&self) -> Result<(), String>;

    /// Decodes the payload (producer and body) of a readable older format `version`
    /// (`KIND.oldest_readable_version()` up to the current one) into the current layout.
    fn decode_older(version: u16, _payload: &[u8]) -> Result<(Producer, Self), String> {
        Err(format!("format version {version} of {} has no reader", Self::KIND.name()))
    }
}

/// The fixed header of an artifact, as read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ArtifactHeader {
    pub kind: ArtifactKind,
    pub version: u16,
    pub payload_len: u64,
    pub checksum: ContentHash,
}

/// Encodes an artifact (header + payload) to bytes; returns them with the content hash.
pub fn encode_artifact<T: ArtifactBody>(producer: &Producer, body: &T) -> (Vec<u8>, ContentHash) {
    let payload = codec::encode(&(producer, body));
    let hash = ContentHash::of(&payload);
    let mut bytes = Vec::with_capacity(HEADER_LEN + payload.len());
    bytes.extend_from_slice(&header::<T>(payload.len(), &hash));
    bytes.extend_from_slice(&payload);
    (bytes, hash)
}

/// The header of an artifact of kind `T` whose payload has `payload_len` bytes and
/// content `hash`.
fn header<T: ArtifactBody>(payload_len: usize, hash: &ContentHash) -> [u8; HEADER_LEN] {
    let mut header = [0u8; HEADER_LEN];
    header[..MAGIC.len()].copy_from_slice(&MAGIC);
    header[8..10].copy_from_slice(&(T::KIND as u16).to_le_bytes());
    header[10..12].copy_from_slice(&T::KIND.current_version().to_le_bytes());
    // Bytes 12..16 are reserved and stay zero.
    header[16..24].copy_from_slice(&(payload_len as u64).to_le_bytes());
    header[24..56].copy_from_slice(&hash.0);
    header
}

/// Writes an artifact atomically; returns its content hash: [`encode_artifact`]'s bytes,
/// without ever holding them. The payload is encoded twice, first into its hash (the
/// header, written first, holds its length and checksum), then into the file: a pose
/// set's payload is hundreds of megabytes, and encoding it again costs less than
/// keeping it. Encoding is deterministic, so both passes see the same bytes.
pub fn write_artifact<T: ArtifactBody>(
    path: &Path,
    producer: &Producer,
    body: &T,
) -> Result<ContentHash, IoError> {
    use std::io::{BufWriter, Write as _};
    let mut hasher = blake3::Hasher::new();
    let payload_len = {
        // Bincode writes field by field; the hasher is fastest fed whole blocks.
        let mut sink = BufWriter::with_capacity(1 << 16, &mut hasher);
        let len = codec::encode_into(&(producer, body), &mut sink).map_err(|e| IoError::io(path, e))?;
        sink.flush().map_err(|e| IoError::io(path, e))?;
        len
    };
    let hash = ContentHash(*hasher.finalize().as_bytes());
    crate::atomic::write_atomic_with(path, |w| {
        w.write_all(&header::<T>(payload_len, &hash))?;
        codec::encode_into(&(producer, body), w)?;
        Ok(())
    })?;
    Ok(hash)
}

/// Parses and checks the header of `bytes` (magic, kind code, reserved bytes, length,
/// checksum), without looking at the version. `path` is for messages only.
pub fn check_envelope(path: &Path, bytes: &[u8]) -> Result<ArtifactHeader, IoError> {
    if bytes.len() < MAGIC.len() || bytes[..MAGIC.len()] != MAGIC {
        return Err(IoError::NotAnArtifact { path: path.to_owned() });
    }
    if bytes.len() < HEADER_LEN {
        return Err(IoError::TruncatedHeader { path: path.to_owned(), found: bytes.len() as u64 });
    }
    let u16_at = |at: usize| u16::from_le_bytes([bytes[at], bytes[at + 1]]);
    let code = u16_at(8);
    let kind =
        ArtifactKind::from_code(code).ok_or_else(|| IoError::UnknownKind { path: path.to_owned(), code })?;
    if bytes[12..16] != [0; 4] {
        return Err(IoError::BadHeader { path: path.to_owned() });
    }
    let payload_len = u64::from_le_bytes(bytes[16..24].try_into().expect("8 bytes"));
    let mut checksum = [0u8; 32];
    checksum.copy_from_slice(&bytes[24..56]);
    let found = (bytes.len() - HEADER_LEN) as u64;
    if found < payload_len {
        return Err(IoError::Truncated { path: path.to_owned(), expected: payload_len, found });
    }
    if found > payload_len {
        return Err(IoError::TrailingBytes { path: path.to_owned(), expected: payload_len, found });
    }
    let checksum = ContentHash(checksum);
    if ContentHash::of(&bytes[HEADER_LEN..]) != checksum {
        return Err(IoError::Checksum { path: path.to_owned() });
    }
    Ok(ArtifactHeader { kind, version: u16_at(10), payload_len, checksum })
}

/// Checks that `bytes` hold a sound artifact of kind `T::KIND` in this build's version,
/// without decoding the payload.
pub fn check_artifact<T: ArtifactBody>(path: &Path, bytes: &[u8]) -> Result<ArtifactHeader, IoError> {
    let header = check_envelope(path, bytes)?;
    if header.kind != T::KIND {
        return Err(IoError::WrongKind {
            path: path.to_owned(),
            expected: T::KIND.name(),
            found: header.kind.name().into(),
        });
    }
    check_version(path, &header)?;
    Ok(header)
}

/// Decodes an artifact of kind `T::KIND` from `bytes`; returns the producer, the body and
/// the content hash. `path` is for messages only.
pub fn decode_artifact<T: ArtifactBody>(
    path: &Path,
    bytes: &[u8],
) -> Result<(Producer, T, ContentHash), IoError> {
    let header = check_artifact::<T>(path, bytes)?;
    let payload = &bytes[HEADER_LEN..];
    let decoded = match header.version < T::KIND.current_version() {
        true => T::decode_older(header.version, payload),
        false => codec::decode(payload),
    };
    let (producer, body): (Producer, T) =
        decoded.map_err(|reason| IoError::Decode { path: path.to_owned(), reason })?;
    body.validate().map_err(|reason| IoError::InvalidArtifact {
        path: path.to_owned(),
        kind: T::KIND.name(),
        reason,
    })?;
    Ok((producer, body, header.checksum))
}

/// Reads and decodes an artifact file of kind `T::KIND` (a regular file only).
pub fn read_artifact<T: ArtifactBody>(path: &Path) -> Result<(Producer, T, ContentHash), IoError> {
    let bytes = crate::file::read_regular_file(path)?;
    decode_artifact(path, &bytes)
}

/// True when the file at `path` is a regular file that starts with the artifact magic
/// (false when unreadable, and without opening a FIFO or device).
pub fn is_artifact(path: &Path) -> bool {
    use std::io::Read;
    if !std::fs::metadata(path).is_ok_and(|m| m.is_file()) {
        return false;
    }
    let mut magic = [0u8; 8];
    std::fs::File::open(path).and_then(|mut f| f.read_exact(&mut magic)).is_ok() && magic == MAGIC
}

/// Reads any artifact's header and producer (for `desal inspect`), checking the whole
/// envelope.
pub fn read_producer(path: &Path) -> Result<(ArtifactHeader, Producer), IoError> {
    let bytes = crate::file::read_regular_file(path)?;
    decode_producer(path, &bytes)
}

/// The header and producer of the artifact in `bytes`, checking the whole envelope.
/// `path` is for messages only.
pub fn decode_producer(path: &Path, bytes: &[u8]) -> Result<(ArtifactHeader, Producer), IoError> {
    let header = check_envelope(path, bytes)?;
    check_version(path, &header)?;
    let (producer, _) = codec::decode_prefix::<Producer>(&bytes[HEADER_LEN..])
        .map_err(|reason| IoError::Decode { path: path.to_owned(), reason })?;
    Ok((header, producer))
}

fn check_version(path: &Path, header: &ArtifactHeader) -> Result<(), IoError> {
    let supported = header.kind.current_version();
    if header.version > supported {
        return Err(IoError::NewerVersion {
            path: path.to_owned(),
            kind: header.kind.name(),
            found: header.version,
            supported,
        });
    }
    if header.version < header.kind.oldest_readable_version() {
        return Err(IoError::OlderVersion {
            path: path.to_owned(),
            kind: header.kind.name(),
            found: header.version,
            supported: header.kind.oldest_readable_version(),
        });
    }
    Ok(())
}
