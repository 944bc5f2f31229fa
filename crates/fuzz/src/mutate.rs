//! The mutations: what a damaged file, a hand edit or a forger does to bytes. Each input
//! gets one to four stacked mutations, chosen by a seeded RNG, so a run is reproducible
//! from `(seed, target, iteration)` alone. The containers whose checks would refuse
//! nearly every byte mutant have structural mutations of their own: [`gltf`] (`.gltf`
//! and `.glb` rigs) and [`npz`] (`hierarchy.npz`).

pub mod gltf;
pub mod npz;

use rand::Rng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;

/// Integers that break length and index arithmetic.
const INTERESTING: [u64; 16] = [
    0,
    1,
    2,
    3,
    0x7f,
    0x80,
    0xff,
    0x7fff,
    0xffff,
    0x7fff_ffff,
    0xffff_ffff,
    1 << 32,
    (1 << 32) + 1,
    1 << 41,
    i64::MAX as u64,
    u64::MAX,
];

/// Decimal tokens that break parsers of counts, indices and coordinates.
const INTERESTING_TEXT: [&str; 16] = [
    "0",
    "-1",
    "1",
    "3",
    "255",
    "256",
    "65536",
    "4294967295",
    "4294967297",
    "1000000000000",
    "1000000000000000000",
    "18446744073709551616",
    "99999999999999999999999",
    "nan",
    "1e400",
    "-0",
];

/// Words of the formats' headers and syntax, for header-line edits.
const KEYWORDS: [&str; 34] = [
    "ply",
    "format",
    "ascii",
    "binary_little_endian",
    "binary_big_endian",
    "1.0",
    "2.0",
    "element",
    "property",
    "list",
    "uchar",
    "int",
    "uint",
    "float",
    "double",
    "vertex",
    "face",
    "vertex_indices",
    "vertex_index",
    "end_header",
    "comment",
    "OFF",
    "COFF",
    "v",
    "f",
    "vn",
    "#",
    "# ids:",
    "0=a,",
    "\"parts\"",
    "\"labels\"",
    "[",
    "]",
    "null",
];

/// Text that user-given names (parts, joints, animations) hold and readers of names get
/// wrong: combining marks, right-to-left text and its override, a zero-width joiner
/// sequence, a byte-order mark, a NUL, a line separator, non-ASCII digits, and JSON
/// escapes of a NUL and of lone surrogates.
const UNICODE_TEXT: [&str; 14] = [
    "e\u{301}\u{301}",
    "\u{5d9}\u{5d3}",
    "\u{202e}",
    "\u{1f469}\u{200d}\u{1f52c}",
    "\u{feff}",
    "\u{0}",
    "\u{2028}",
    "\u{663}\u{ff11}",
    "\u{10ffff}",
    "\\u0000",
    "\\ud800",
    "\\udc00\\ud800",
    "\\ud83d\\ude00",
    "\u{1d573}",
];

/// Byte sequences that are not UTF-8: overlong encodings of `/` and NUL, a UTF-16
/// surrogate, a code point past U+10FFFF, a lone continuation byte, a cut sequence.
const BAD_UTF8: [&[u8]; 7] = [
    &[0xc0, 0xaf],
    &[0xc0, 0x80],
    &[0xe0, 0x80, 0xaf],
    &[0xed, 0xa0, 0x80],
    &[0xf4, 0x90, 0x80, 0x80],
    &[0x80],
    &[0xe2, 0x82],
];

/// A mutated copy of `seed`; `donor` is another seed of the same target, for splices.
pub fn mutate(rng: &mut ChaCha8Rng, seed: &[u8], donor: &[u8]) -> Vec<u8> {
    let mut bytes = seed.to_vec();
    for _ in 0..rng.gen_range(1..=4) {
        match rng.gen_range(0..10) {
            0 => flip_bits(rng, &mut bytes),
            1 => set_byte(rng, &mut bytes),
            2 => insert_bytes(rng, &mut bytes),
            3 => delete_range(rng, &mut bytes),
            4 => bytes = splice(rng, &bytes, donor),
            5 => write_integer(rng, &mut bytes),
            6 => write_varint_length(rng, &mut bytes),
            7 => replace_number_token(rng, &mut bytes),
            8 => insert_unicode(rng, &mut bytes),
            _ => edit_header_line(rng, &mut bytes),
        }
    }
    bytes
}

/// An offset into `bytes`, biased to the first 512 bytes, where headers and length
/// prefixes live (half the time).
fn offset(rng: &mut ChaCha8Rng, len: usize) -> usize {
    if len == 0 {
        return 0;
    }
    if rng.gen_bool(0.5) { rng.gen_range(0..len.min(512)) } else { rng.gen_range(0..len) }
}

fn flip_bits(rng: &mut ChaCha8Rng, bytes: &mut [u8]) {
    for _ in 0..rng.gen_range(1..=8) {
        if bytes.is_empty() {
            return;
        }
        let at = offset(rng, bytes.len());
        bytes[at] ^= 1 << rng.gen_range(0..8);
    }
}

fn set_byte(rng: &mut ChaCha8Rng, bytes: &mut [u8]) {
    if !bytes.is_empty() {
        let at = offset(rng, bytes.len());
        bytes[at] = *[0u8, 0xff, b'\n', b' ', b'-', b'9', rng.r#gen()].choose(rng).expect("non-empty");
    }
}

fn insert_bytes(rng: &mut ChaCha8Rng, bytes: &mut Vec<u8>) {
    let at = offset(rng, bytes.len() + 1).min(bytes.len());
    let count = rng.gen_range(1..=16);
    let new: Vec<u8> = (0..count).map(|_| rng.r#gen()).collect();
    bytes.splice(at..at, new);
}

fn delete_range(rng: &mut ChaCha8Rng, bytes: &mut Vec<u8>) {
    if bytes.is_empty() {
        return;
    }
    let at = offset(rng, bytes.len());
    let end = (at + rng.gen_range(1..=64)).min(bytes.len());
    bytes.drain(at..end);
}

/// A prefix of `bytes` followed by a suffix of `donor`.
fn splice(rng: &mut ChaCha8Rng, bytes: &[u8], donor: &[u8]) -> Vec<u8> {
    let cut = rng.gen_range(0..=bytes.len());
    let from = rng.gen_range(0..=donor.len());
    [&bytes[..cut], &donor[from..]].concat()
}

/// Tricky text ([`UNICODE_TEXT`]) or bytes that are not UTF-8 ([`BAD_UTF8`]), inserted
/// or written over a character, at the start of a name when the input has one: after a
/// `"`, a `=` or a space, where the formats keep part names.
fn insert_unicode(rng: &mut ChaCha8Rng, bytes: &mut Vec<u8>) {
    let new: &[u8] = if rng.gen_bool(0.7) {
        UNICODE_TEXT.choose(rng).expect("non-empty").as_bytes()
    } else {
        BAD_UTF8.choose(rng).expect("non-empty")
    };
    let start = offset(rng, bytes.len() + 1).min(bytes.len());
    let at =
        bytes[start..].iter().position(|b| matches!(b, b'"' | b'=' | b' ')).map_or(start, |k| start + k + 1);
    let end = if rng.gen_bool(0.3) { (at + 1).min(bytes.len()) } else { at };
    bytes.splice(at..end, new.iter().copied());
}

/// An interesting integer, 1, 2, 4 or 8 bytes wide, little- or big-endian, over the
/// bytes at a random offset (binary counts, list lengths, indices).
fn write_integer(rng: &mut ChaCha8Rng, bytes: &mut Vec<u8>) {
    let value = *INTERESTING.choose(rng).expect("non-empty");
    let width = *[1usize, 2, 4, 8].choose(rng).expect("non-empty");
    let le = value.to_le_bytes();
    let be = value.to_be_bytes();
    let encoded: Vec<u8> = if rng.gen_bool(0.5) { le[..width].to_vec() } else { be[8 - width..].to_vec() };
    overwrite(rng, bytes, &encoded);
}

/// A bincode varint length prefix (marker 251/252/253 and a large value) over the
/// bytes at a random offset: the forged lengths of D9.
fn write_varint_length(rng: &mut ChaCha8Rng, bytes: &mut Vec<u8>) {
    let value = *INTERESTING.choose(rng).expect("non-empty");
    let mut encoded = Vec::with_capacity(9);
    match rng.gen_range(0..3) {
        0 => {
            encoded.push(251);
            encoded.extend_from_slice(&(value as u16).to_le_bytes());
        }
        1 => {
            encoded.push(252);
            encoded.extend_from_slice(&(value as u32).to_le_bytes());
        }
        _ => {
            encoded.push(253);
            encoded.extend_from_slice(&value.to_le_bytes());
        }
    }
    overwrite(rng, bytes, &encoded);
}

fn overwrite(rng: &mut ChaCha8Rng, bytes: &mut Vec<u8>, new: &[u8]) {
    let at = offset(rng, bytes.len() + 1).min(bytes.len());
    let end = (at + new.len()).min(bytes.len());
    bytes.splice(at..end, new.iter().copied());
}

/// Replaces one run of ASCII digits (a count, an index, a coordinate) with an
/// interesting decimal token: the text formats' length-field edit.
fn replace_number_token(rng: &mut ChaCha8Rng, bytes: &mut Vec<u8>) {
    if bytes.is_empty() {
        return;
    }
    let start = offset(rng, bytes.len());
    let Some(first) = bytes[start..].iter().position(u8::is_ascii_digit).map(|k| start + k) else { return };
    let end = bytes[first..].iter().position(|b| !b.is_ascii_digit()).map_or(bytes.len(), |k| first + k);
    let token = INTERESTING_TEXT.choose(rng).expect("non-empty");
    bytes.splice(first..end, token.bytes());
}

/// A line among the first 16 (the header of PLY and OFF, the first records of OBJ and
/// labels) duplicated, deleted, swapped with the next, or given a keyword.
fn edit_header_line(rng: &mut ChaCha8Rng, bytes: &mut Vec<u8>) {
    let mut starts: Vec<usize> = vec![0];
    starts.extend(bytes.iter().enumerate().filter(|&(_, &b)| b == b'\n').map(|(k, _)| k + 1).take(16));
    let line = rng.gen_range(0..starts.len());
    let start = starts[line].min(bytes.len());
    let end = starts.get(line + 1).copied().unwrap_or(bytes.len()).min(bytes.len());
    let text = bytes[start..end].to_vec();
    match rng.gen_range(0..4) {
        0 => {
            bytes.splice(start..start, text);
        }
        1 => {
            bytes.drain(start..end);
        }
        2 => {
            if let Some(&next_end) = starts.get(line + 2) {
                let next_end = next_end.min(bytes.len());
                let next = bytes[end..next_end].to_vec();
                bytes.splice(start..next_end, next.into_iter().chain(text));
            }
        }
        _ => {
            // Replace one word of the line, or append one.
            let words: Vec<(usize, usize)> = word_spans(&text);
            let keyword = KEYWORDS.choose(rng).expect("non-empty").as_bytes();
            match words.choose(rng) {
                Some(&(a, b)) if rng.gen_bool(0.8) => {
                    bytes.splice(start + a..start + b, keyword.iter().copied());
                }
                _ => {
                    let at = end.saturating_sub(1).max(start);
                    bytes.splice(at..at, [b' '].into_iter().chain(keyword.iter().copied()));
                }
            }
        }
    }
}

/// `(start, end)` of every space-separated word of `line`.
fn word_spans(line: &[u8]) -> Vec<(usize, usize)> {
    let mut spans = Vec::new();
    let mut start = None;
    for (k, &b) in line.iter().enumerate() {
        let blank = b == b' ' || b == b'\t' || b == b'\n' || b == b'\r';
        match (start, blank) {
            (None, false) => start = Some(k),
            (Some(s), true) => {
                spans.push((s, k));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        spans.push((s, line.len()));
    }
    spans
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    /// The same RNG state gives the same mutant: a finding is reproducible from its seed.
    #[test]
    fn mutation_is_deterministic_and_changes_the_input() {
        let seed = b"ply\nformat ascii 1.0\nelement vertex 3\nend_header\n0 0 0\n".to_vec();
        let mut changed = 0;
        for k in 0..200 {
            let a = mutate(&mut ChaCha8Rng::seed_from_u64(k), &seed, b"donor");
            let b = mutate(&mut ChaCha8Rng::seed_from_u64(k), &seed, b"donor");
            assert_eq!(a, b);
            changed += usize::from(a != seed);
        }
        assert!(changed > 180, "only {changed} of 200 mutants differ from the seed");
    }

    #[test]
    fn number_tokens_are_replaced_whole() {
        let spans = word_spans(b"element vertex 12\n");
        assert_eq!(spans, vec![(0, 7), (8, 14), (15, 17)]);
    }
}
