//! Structural mutations of `.npz` files (a zip of stored `.npy` entries). A byte flip in
//! a payload fails the CRC, so the decoder behind it would never be reached; here most
//! mutants are taken apart into (name, `.npy` bytes) entries, edited where the reader
//! trusts the file — the npy header's `shape`, `descr`, `fortran_order` and version, the
//! header length, the data, the entry names and their order — and zipped again with
//! valid CRCs and offsets (as a forger would), and then perhaps one field of a local
//! header, a central directory record or the end record is given a lying value.

use rand::Rng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;

const LOCAL_SIGNATURE: u32 = 0x0403_4b50;
const CENTRAL_SIGNATURE: u32 = 0x0201_4b50;
const END_SIGNATURE: u32 = 0x0605_4b50;

const SHAPES: [&str; 14] = [
    "()",
    "(0,)",
    "(1,)",
    "(3,)",
    "(-1,)",
    "(0, 3)",
    "(7, 3)",
    "(3, 7)",
    "(4294967296, 4294967296)",
    "(18446744073709551615,)",
    "(18446744073709551616,)",
    "(2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2)",
    "(1,,2)",
    "(a)",
];
const DESCRS: [&str; 12] = [
    "'<i4'", "'<i8'", "'<f8'", "'>i4'", "'|u1'", "'<f4'", "'|O'", "'<U8'", "'<c16'", "\"<i4\"", "'<i4", "''",
];
const NAMES: [&str; 9] = ["levels", "F0", "A0_row", "A0_shape", "map1", "../x", "", "é\u{301}", "levels.npy"];

/// One entry of the archive: its file name and its `.npy` bytes.
type Entry = (Vec<u8>, Vec<u8>);

/// A mutant of the npz `seed`; `donor` is another seed.
pub fn mutate_npz(rng: &mut ChaCha8Rng, seed: &[u8], donor: &[u8]) -> Vec<u8> {
    if rng.gen_bool(0.1) {
        return super::mutate(rng, seed, donor);
    }
    let Some(mut entries) = entries(seed) else { return super::mutate(rng, seed, donor) };
    for _ in 0..rng.gen_range(1..=3) {
        edit_entries(rng, &mut entries, donor);
    }
    let (mut bytes, fields) = zip(&entries, rng.gen_bool(0.95));
    if rng.gen_bool(0.3) {
        lie_in_a_field(rng, &mut bytes, &fields);
    }
    if rng.gen_bool(0.05) { super::mutate(rng, &bytes, donor) } else { bytes }
}

/// The (name, `.npy` bytes) entries of a well-formed zip of stored entries, walked by
/// their local headers; `None` when the walk runs off the end.
pub fn entries(bytes: &[u8]) -> Option<Vec<Entry>> {
    let u16_at = |at: usize| Some(u16::from_le_bytes(bytes.get(at..at + 2)?.try_into().ok()?) as usize);
    let u32_at = |at: usize| Some(u32::from_le_bytes(bytes.get(at..at + 4)?.try_into().ok()?));
    let mut out = Vec::new();
    let mut at = 0;
    while u32_at(at)? == LOCAL_SIGNATURE {
        let size = u32_at(at + 18)? as usize;
        let (name_len, extra_len) = (u16_at(at + 26)?, u16_at(at + 28)?);
        let name = bytes.get(at + 30..at + 30 + name_len)?.to_vec();
        let start = at + 30 + name_len + extra_len;
        out.push((name, bytes.get(start..start + size)?.to_vec()));
        at = start + size;
    }
    Some(out)
}

fn edit_entries(rng: &mut ChaCha8Rng, entries: &mut Vec<Entry>, donor: &[u8]) {
    if entries.is_empty() {
        return;
    }
    let i = rng.gen_range(0..entries.len());
    match rng.gen_range(0..8) {
        0..=2 => edit_npy_header(rng, &mut entries[i].1),
        3 => edit_npy_data(rng, &mut entries[i].1),
        4 => {
            let name = NAMES.choose(rng).expect("non-empty");
            entries[i].0 =
                if rng.gen_bool(0.8) { format!("{name}.npy").into_bytes() } else { vec![0xc0, 0xaf] };
        }
        5 => {
            let copy = entries[i].clone();
            entries.insert(rng.gen_range(0..=entries.len()), copy);
        }
        6 => {
            entries.remove(i);
        }
        _ => {
            // An entry of the other seed under this entry's name (another level's array).
            if let Some(other) = self::entries(donor).and_then(|d| d.choose(rng).cloned()) {
                entries[i].1 = other.1;
            }
        }
    }
}

/// Rewrites one value of the npy header's dict, or its version or length bytes. When the
/// new shape is small, the data is resized to match it half the time, so the check that
/// shape and size agree passes and the values are decoded.
fn edit_npy_header(rng: &mut ChaCha8Rng, npy: &mut Vec<u8>) {
    if npy.len() < 10 {
        return;
    }
    match rng.gen_range(0..6) {
        0 => npy[6] = *[0u8, 1, 2, 3, 4, 255].choose(rng).expect("non-empty"),
        1 => {
            let len = *[0u16, 1, 10, 118, 0xffff].choose(rng).expect("non-empty");
            npy[8..10].copy_from_slice(&len.to_le_bytes());
        }
        _ => {
            let header_len = u16::from_le_bytes([npy[8], npy[9]]) as usize;
            let Some(header) = npy.get(10..10 + header_len).and_then(|h| std::str::from_utf8(h).ok()) else {
                return;
            };
            let (key, value) = match rng.gen_range(0..4) {
                0 => ("descr", DESCRS.choose(rng).expect("non-empty").to_string()),
                1 => ("fortran_order", ["True", "1", "False"].choose(rng).expect("non-empty").to_string()),
                2 => ("nonsense", String::new()),
                _ => ("shape", SHAPES.choose(rng).expect("non-empty").to_string()),
            };
            let new_header = match (header.find(&format!("'{key}': ")), key) {
                (Some(start), _) => {
                    let value_start = start + key.len() + 4;
                    let rest = &header[value_start..];
                    let end =
                        if rest.starts_with('(') { rest.find(')').map(|e| e + 1) } else { rest.find(',') };
                    let end = value_start + end.unwrap_or(rest.len());
                    format!("{}{value}{}", &header[..value_start], &header[end..])
                }
                // Drops a key (the `nonsense` edit), or another whole dict.
                _ => header.replacen("'shape'", "'shap'", 1),
            };
            let mut data = npy[10 + header_len..].to_vec();
            if key == "shape" && rng.gen_bool(0.5) {
                let dims: Option<Vec<usize>> = value
                    .trim_matches(|c| c == '(' || c == ')')
                    .split(',')
                    .filter(|s| !s.trim().is_empty())
                    .map(|s| s.trim().parse().ok())
                    .collect();
                if let Some(count) = dims.and_then(|d| d.iter().try_fold(1usize, |a, &x| a.checked_mul(x)))
                    && count <= 4096
                {
                    let item = if header.contains("<i4") { 4 } else { 8 };
                    data.resize(count * item, 0);
                }
            }
            let mut out = npy[..8].to_vec();
            out.extend_from_slice(&(new_header.len() as u16).to_le_bytes());
            out.extend_from_slice(new_header.as_bytes());
            out.extend_from_slice(&data);
            *npy = out;
        }
    }
}

/// Writes an integer or float that breaks what the hierarchy's arrays promise (a
/// negative or huge index, a NaN) over the data, or cuts it.
fn edit_npy_data(rng: &mut ChaCha8Rng, npy: &mut Vec<u8>) {
    let header_len = npy.get(8..10).map_or(0, |b| u16::from_le_bytes([b[0], b[1]]) as usize);
    let start = 10 + header_len;
    if npy.len() <= start {
        return;
    }
    let value: Vec<u8> = match rng.gen_range(0..3) {
        0 => [-1i32, i32::MAX, i32::MIN, 65536].choose(rng).expect("non-empty").to_le_bytes().to_vec(),
        1 => [-1i64, i64::MAX, 1 << 40].choose(rng).expect("non-empty").to_le_bytes().to_vec(),
        _ => [f64::NAN, f64::INFINITY, -0.0].choose(rng).expect("non-empty").to_le_bytes().to_vec(),
    };
    let at = start + rng.gen_range(0..npy.len() - start);
    let at = at - (at - start) % 4;
    let end = (at + value.len()).min(npy.len());
    npy[at..end].copy_from_slice(&value[..end - at]);
    if rng.gen_bool(0.1) {
        npy.truncate(rng.gen_range(start..npy.len()));
    }
}

/// Where each header field of a zip written by [`zip`] lies: `(offset, width)`.
type Fields = Vec<(usize, usize)>;

/// Zips `entries` as stored entries (CRCs right when `good_crc`), returning the bytes and
/// the offsets of every header field a forger would edit.
fn zip(entries: &[Entry], good_crc: bool) -> (Vec<u8>, Fields) {
    let mut out = Vec::new();
    let mut central = Vec::new();
    let mut fields = Vec::new();
    let mut central_fields = Vec::new();
    for (name, payload) in entries {
        let crc = if good_crc { crc32fast::hash(payload) } else { 0 };
        let offset = out.len() as u32;
        let at = out.len();
        out.extend(LOCAL_SIGNATURE.to_le_bytes());
        out.extend([20u16, 0, 0, 0, 33].iter().flat_map(|v| v.to_le_bytes()));
        out.extend([crc, payload.len() as u32, payload.len() as u32].iter().flat_map(|v| v.to_le_bytes()));
        out.extend([name.len() as u16, 0].iter().flat_map(|v| v.to_le_bytes()));
        // signature, method, crc, sizes, name length, extra length
        fields.extend([
            (at, 4),
            (at + 8, 2),
            (at + 14, 4),
            (at + 18, 4),
            (at + 22, 4),
            (at + 26, 2),
            (at + 28, 2),
        ]);
        out.extend_from_slice(name);
        out.extend_from_slice(payload);

        let c = central.len();
        central.extend(CENTRAL_SIGNATURE.to_le_bytes());
        central.extend([20u16, 20, 0, 0, 0, 33].iter().flat_map(|v| v.to_le_bytes()));
        central
            .extend([crc, payload.len() as u32, payload.len() as u32].iter().flat_map(|v| v.to_le_bytes()));
        central.extend([name.len() as u16, 0, 0, 0, 0].iter().flat_map(|v| v.to_le_bytes()));
        central.extend(0u32.to_le_bytes());
        central.extend(offset.to_le_bytes());
        // signature, method, crc, sizes, name/extra/comment lengths, local header offset
        central_fields.extend([
            (c, 4),
            (c + 10, 2),
            (c + 16, 4),
            (c + 20, 4),
            (c + 24, 4),
            (c + 28, 2),
            (c + 30, 2),
            (c + 32, 2),
            (c + 42, 4),
        ]);
        central.extend_from_slice(name);
    }
    let central_offset = out.len();
    fields.extend(central_fields.into_iter().map(|(at, w)| (central_offset + at, w)));
    out.extend_from_slice(&central);
    let end = out.len();
    out.extend(END_SIGNATURE.to_le_bytes());
    out.extend([0u16, 0, entries.len() as u16, entries.len() as u16].iter().flat_map(|v| v.to_le_bytes()));
    out.extend((central.len() as u32).to_le_bytes());
    out.extend((central_offset as u32).to_le_bytes());
    out.extend(0u16.to_le_bytes());
    // entries here, entries in all, central size, central offset, comment length
    fields.extend([(end + 8, 2), (end + 10, 2), (end + 12, 4), (end + 16, 4), (end + 20, 2)]);
    (out, fields)
}

/// Gives one header field a value near its truth or at a limit.
fn lie_in_a_field(rng: &mut ChaCha8Rng, bytes: &mut [u8], fields: &Fields) {
    let Some(&(at, width)) = fields.choose(rng) else { return };
    let truth = bytes[at..at + width].iter().rev().fold(0u64, |acc, &b| acc << 8 | u64::from(b));
    let value = match rng.gen_range(0..3) {
        0 => truth.wrapping_add(rng.gen_range(1..=64)),
        1 => truth.wrapping_sub(rng.gen_range(1..=64)),
        _ => *[0, 1, 8, 0xffff, 0x7fff_ffff, 0xffff_ffff].choose(rng).expect("non-empty"),
    };
    bytes[at..at + width].copy_from_slice(&value.to_le_bytes()[..width]);
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    /// [`zip`] writes what desal-io's writer writes for the same entries, so a mutant
    /// that edits nothing is a file the reader accepts.
    #[test]
    fn rezipping_a_seed_gives_the_seed() {
        let seeds = crate::corpus::seeds(crate::Target::Npz, &crate::corpus::default_root()).unwrap();
        for seed in seeds {
            let parts = entries(&seed.bytes).unwrap();
            assert!(parts.len() > 5);
            assert_eq!(zip(&parts, true).0, seed.bytes, "{}", seed.name);
        }
    }

    /// Edits reach the npy headers: some mutants decode to a shape or dtype no seed has.
    #[test]
    fn header_edits_reach_the_npy_reader() {
        let seeds = crate::corpus::seeds(crate::Target::Npz, &crate::corpus::default_root()).unwrap();
        let seed = &seeds[0].bytes;
        let mut reasons = Vec::new();
        for k in 0..500 {
            let mutant = mutate_npz(&mut ChaCha8Rng::seed_from_u64(k), seed, seed);
            if let Err(e) = desal_io::npz::decode_npz(&mutant) {
                reasons.push(e);
            }
        }
        for expected in ["dtype", "Fortran-order", "shape", "CRC-32", "past the end"] {
            assert!(
                reasons.iter().any(|r| r.contains(expected)),
                "no '{expected}' refusal among {reasons:?}"
            );
        }
    }
}
