//! Mutations of byte strings: AFL-style havoc (bits, bytes, ranges, splices, boundary
//! integers and floats written in binary) and text-aware ones (numbers replaced by boundary
//! values, words swapped for the target's own vocabulary, lines deleted, duplicated, swapped
//! or repeated many times, brackets nested deep).
//!
//! Invariants: a mutation is a pure function of the PRNG state, the input, the other corpus
//! entry it may splice from and the dictionary, so a run is reproduced by its seed; the result
//! never exceeds `max_len` bytes.

/// xorshift64*: small, fast and good enough to pick mutations (not for anything secret).
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        // splitmix64 of the seed, so that small seeds (0, 1, 2) give unrelated streams and
        // the state is never zero.
        let mut z = seed.wrapping_add(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        Rng((z ^ (z >> 31)) | 1)
    }

    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    /// Uniform in `0..n` (`n > 0`).
    pub fn below(&mut self, n: usize) -> usize {
        ((self.next() >> 11) % n as u64) as usize
    }

    pub fn chance(&mut self, numerator: usize, denominator: usize) -> bool {
        self.below(denominator) < numerator
    }

    /// A length skewed towards small values: 1..=max, mostly under 8.
    pub fn small_len(&mut self, max: usize) -> usize {
        let max = max.max(1);
        let cap = match self.below(4) {
            0..=1 => 4,
            2 => 32,
            _ => max,
        };
        1 + self.below(cap.min(max))
    }

    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// Numbers that break readers: zero, signs, the edges of integer types, counts one past
/// `u32`, floats at and past the edges of `f64`, non-numbers.
const TEXT_NUMBERS: &[&str] = &[
    "0",
    "-0",
    "1",
    "-1",
    "2",
    "3",
    "7",
    "255",
    "256",
    "65535",
    "65536",
    "2147483647",
    "2147483648",
    "-2147483648",
    "4294967295",
    "4294967296",
    "4294967297",
    "9223372036854775807",
    "-9223372036854775808",
    "18446744073709551615",
    "18446744073709551616",
    "99999999999999999999999",
    "0.5",
    "-0.5",
    "1e308",
    "-1e308",
    "1e309",
    "1.7976931348623157e308",
    "4.9e-324",
    "1e-320",
    "nan",
    "NaN",
    "-nan",
    "inf",
    "-inf",
    "Infinity",
    "1e",
    "1.2.3",
    "--1",
    "0x10",
    "1_000",
    "",
];

const BINARY_U64: &[u64] = &[
    0,
    1,
    2,
    0x7f,
    0x80,
    0xff,
    0x100,
    0x7fff,
    0x8000,
    0xffff,
    0x1_0000,
    0x7fff_ffff,
    0x8000_0000,
    0xffff_ffff,
    0x1_0000_0001,
    0x7fff_ffff_ffff_ffff,
    0x8000_0000_0000_0000,
    u64::MAX,
];

const BINARY_F64: &[f64] = &[
    0.0,
    -0.0,
    1.0,
    -1.0,
    1e308,
    -1e308,
    f64::MAX,
    f64::MIN_POSITIVE,
    5e-324,
    f64::INFINITY,
    f64::NEG_INFINITY,
    f64::NAN,
    4294967297.0,
];

/// Byte runs that open nesting in the formats we read (TOML arrays and inline tables,
/// expressions, XML elements, quotes).
const OPENERS: &[&[u8]] = &[
    b"[", b"{", b"(", b"a = [", b"x = {", b"<a>", b"\"", b"-", b"@a ",
];

/// Applies a stack of 1 to 8 mutations (`other` is a second corpus entry to splice from).
pub fn mutate(
    rng: &mut Rng,
    input: &[u8],
    other: &[u8],
    dictionary: &[Vec<u8>],
    max_len: usize,
) -> Vec<u8> {
    let mut data = input.to_vec();
    let stack = 1 << rng.below(4);
    for _ in 0..stack {
        mutate_once(rng, &mut data, other, dictionary);
        if data.len() > max_len {
            data.truncate(max_len);
        }
    }
    data
}

fn mutate_once(rng: &mut Rng, data: &mut Vec<u8>, other: &[u8], dictionary: &[Vec<u8>]) {
    if data.is_empty() {
        let len = rng.small_len(64);
        data.extend((0..len).map(|_| rng.next() as u8));
        return;
    }
    match rng.below(20) {
        0 => {
            let bit = rng.below(data.len() * 8);
            data[bit / 8] ^= 1 << (bit % 8);
        }
        1 => {
            let i = rng.below(data.len());
            data[i] = rng.next() as u8;
        }
        2 => {
            // One byte of a structural kind: separators and signs matter most to parsers.
            let i = rng.below(data.len());
            data[i] = *rng.pick(b" \n\t\r,;:=#\"'-+.eE0123456789[]{}()<>/\\$*@\0\xff");
        }
        3 => {
            let at = rng.below(data.len() + 1);
            let len = rng.small_len(32);
            let byte = rng.next() as u8;
            let random = rng.chance(1, 2);
            let bytes: Vec<u8> = (0..len)
                .map(|_| if random { rng.next() as u8 } else { byte })
                .collect();
            data.splice(at..at, bytes);
        }
        4 | 5 => {
            let (start, len) = range(rng, data.len());
            data.drain(start..start + len);
        }
        6 => {
            let (start, len) = range(rng, data.len());
            let chunk = data[start..start + len].to_vec();
            let at = rng.below(data.len() + 1);
            data.splice(at..at, chunk);
        }
        7 => {
            if other.is_empty() {
                return;
            }
            let (start, len) = range(rng, other.len());
            let at = rng.below(data.len() + 1);
            if rng.chance(1, 2) {
                data.splice(at..at, other[start..start + len].iter().copied());
            } else {
                let end = (at + len).min(data.len());
                data.splice(at..end, other[start..start + len].iter().copied());
            }
        }
        8 => {
            // Crossover: a prefix of this entry, a suffix of the other.
            if other.is_empty() {
                return;
            }
            let cut = rng.below(data.len() + 1);
            let from = rng.below(other.len() + 1);
            data.truncate(cut);
            data.extend_from_slice(&other[from..]);
        }
        9..=11 => replace_number(rng, data),
        12 => write_binary_value(rng, data),
        13 => {
            let keep = rng.below(data.len() + 1);
            data.truncate(keep);
        }
        14 | 15 => replace_word(rng, data, dictionary),
        16 => line_edit(rng, data),
        17 => {
            // Many copies of a small piece: huge counts of lines, elements or words.
            let len = rng.small_len(data.len().min(64));
            let start = rng.below(data.len() - len + 1);
            let chunk = data[start..start + len].to_vec();
            let copies = 1 << (4 + rng.below(10));
            let at = rng.below(data.len() + 1);
            let repeated: Vec<u8> = chunk.iter().copied().cycle().take(len * copies).collect();
            data.splice(at..at, repeated);
        }
        18 => {
            let opener = *rng.pick(OPENERS);
            let depth = 1 << (3 + rng.below(13));
            let at = rng.below(data.len() + 1);
            let nested: Vec<u8> = opener
                .iter()
                .copied()
                .cycle()
                .take(opener.len() * depth)
                .collect();
            data.splice(at..at, nested);
        }
        _ => {
            if dictionary.is_empty() {
                return;
            }
            let word = rng.pick(dictionary).clone();
            let at = rng.below(data.len() + 1);
            const SEPARATORS: [&[u8]; 4] = [b" ", b"\n", b"", b"\t"];
            let sep = *rng.pick(&SEPARATORS);
            let mut insert = word;
            insert.extend_from_slice(sep);
            data.splice(at..at, insert);
        }
    }
}

/// A random non-empty range of `0..len` (`len > 0`), usually short.
fn range(rng: &mut Rng, len: usize) -> (usize, usize) {
    let n = rng.small_len(len);
    (rng.below(len - n + 1), n)
}

fn is_number_byte(b: u8) -> bool {
    b.is_ascii_digit() || matches!(b, b'.' | b'-' | b'+' | b'e' | b'E')
}

/// Replaces one ASCII number (a run of digits with its sign, point and exponent) by a
/// boundary value, or by itself plus or minus one, doubled, or negated.
fn replace_number(rng: &mut Rng, data: &mut Vec<u8>) {
    let start = rng.below(data.len());
    let Some(digit) = (start..data.len())
        .chain(0..start)
        .find(|&i| data[i].is_ascii_digit())
    else {
        return;
    };
    let mut a = digit;
    while a > 0 && is_number_byte(data[a - 1]) {
        a -= 1;
    }
    let mut b = digit;
    while b < data.len() && is_number_byte(data[b]) {
        b += 1;
    }
    let old = std::str::from_utf8(&data[a..b]).unwrap_or("0");
    let new = match rng.below(4) {
        0 => match old.parse::<i128>() {
            Ok(v) => {
                let delta = [1i128, -1, v, v.saturating_mul(-2)][rng.below(4)];
                v.saturating_add(delta).to_string()
            }
            Err(_) => rng.pick(TEXT_NUMBERS).to_string(),
        },
        _ => rng.pick(TEXT_NUMBERS).to_string(),
    };
    data.splice(a..b, new.into_bytes());
}

/// Overwrites 1, 2, 4 or 8 bytes at a random offset with a boundary integer (either byte
/// order) or a boundary `f32`/`f64`.
fn write_binary_value(rng: &mut Rng, data: &mut [u8]) {
    let bytes: Vec<u8> = match rng.below(4) {
        0 | 1 => {
            let v = *rng.pick(BINARY_U64);
            let v = if rng.chance(1, 3) {
                v.wrapping_neg()
            } else {
                v
            };
            let width = 1 << rng.below(4);
            let le = v.to_le_bytes();
            let mut b = le[..width].to_vec();
            if rng.chance(1, 2) {
                b.reverse();
            }
            b
        }
        2 => {
            let v = *rng.pick(BINARY_F64);
            let b = v.to_le_bytes().to_vec();
            if rng.chance(1, 2) {
                b.into_iter().rev().collect()
            } else {
                b
            }
        }
        _ => {
            let v = *rng.pick(BINARY_F64) as f32;
            let b = v.to_le_bytes().to_vec();
            if rng.chance(1, 2) {
                b.into_iter().rev().collect()
            } else {
                b
            }
        }
    };
    if bytes.len() > data.len() {
        return;
    }
    let at = rng.below(data.len() - bytes.len() + 1);
    data[at..at + bytes.len()].copy_from_slice(&bytes);
}

fn is_word_byte(b: u8) -> bool {
    b.is_ascii_alphanumeric() || matches!(b, b'_' | b'$' | b'.' | b'*')
}

/// Replaces one word of the input by a word of the dictionary (or of the input itself).
fn replace_word(rng: &mut Rng, data: &mut Vec<u8>, dictionary: &[Vec<u8>]) {
    let start = rng.below(data.len());
    let Some(hit) = (start..data.len())
        .chain(0..start)
        .find(|&i| is_word_byte(data[i]))
    else {
        return;
    };
    let mut a = hit;
    while a > 0 && is_word_byte(data[a - 1]) {
        a -= 1;
    }
    let mut b = hit;
    while b < data.len() && is_word_byte(data[b]) {
        b += 1;
    }
    let new = if dictionary.is_empty() || rng.chance(1, 4) {
        let words = words_of(data);
        if words.is_empty() {
            return;
        }
        rng.pick(&words).clone()
    } else {
        rng.pick(dictionary).clone()
    };
    data.splice(a..b, new);
}

/// Deletes, duplicates, swaps or moves whole lines.
fn line_edit(rng: &mut Rng, data: &mut Vec<u8>) {
    let mut lines: Vec<Vec<u8>> = data
        .split_inclusive(|&b| b == b'\n')
        .map(<[u8]>::to_vec)
        .collect();
    if lines.is_empty() {
        return;
    }
    let i = rng.below(lines.len());
    match rng.below(4) {
        0 => {
            let n = rng.small_len(lines.len() - i);
            lines.drain(i..i + n);
        }
        1 => {
            let line = lines[i].clone();
            let copies = rng.small_len(8);
            for _ in 0..copies {
                lines.insert(i, line.clone());
            }
        }
        2 => {
            let j = rng.below(lines.len());
            lines.swap(i, j);
        }
        _ => {
            let line = lines.remove(i);
            let j = rng.below(lines.len() + 1);
            lines.insert(j, line);
        }
    }
    *data = lines.concat();
}

/// The distinct words (runs of letters, digits, `_$.*`) of `text`, in order of appearance,
/// at most `limit`: the target's vocabulary, harvested from its seeds.
pub fn vocabulary<'a>(texts: impl Iterator<Item = &'a [u8]>, limit: usize) -> Vec<Vec<u8>> {
    let mut seen = std::collections::HashSet::new();
    let mut out = Vec::new();
    for text in texts {
        for word in words_of(text) {
            // Numbers are better served by `replace_number`; long words are data, not syntax.
            if word.len() > 40 || word.iter().all(|b| b.is_ascii_digit() || *b == b'.') {
                continue;
            }
            if seen.insert(word.clone()) {
                out.push(word);
                if out.len() == limit {
                    return out;
                }
            }
        }
    }
    out
}

fn words_of(data: &[u8]) -> Vec<Vec<u8>> {
    data.split(|&b| !is_word_byte(b))
        .filter(|w| !w.is_empty())
        .take(10_000)
        .map(<[u8]>::to_vec)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_seed_reproduces_its_mutations_and_lengths_stay_bounded() {
        let input = b"$Nodes\n1 0 0 0\n2 1.5e3 -2 4\n$EndNodes\n".to_vec();
        let other = b"solid x\nfacet normal 0 0 1\nendsolid\n".to_vec();
        let dictionary = vocabulary([input.as_slice(), other.as_slice()].into_iter(), 100);
        let run = |seed| {
            let mut rng = Rng::new(seed);
            (0..500)
                .map(|_| mutate(&mut rng, &input, &other, &dictionary, 4096))
                .collect::<Vec<_>>()
        };
        let a = run(7);
        assert_eq!(a, run(7));
        assert_ne!(a, run(8));
        assert!(a.iter().all(|m| m.len() <= 4096));
        // The havoc reaches every kind of change: some outputs shrink, some grow, and some
        // keep the length with different bytes.
        assert!(a.iter().any(|m| m.len() < input.len()));
        assert!(a.iter().any(|m| m.len() > input.len()));
        assert!(a.iter().any(|m| m.len() == input.len() && *m != input));
        // Numbers are replaced by boundary values.
        assert!(a.iter().any(|m| m.windows(10).any(|w| w == b"4294967297")));
    }

    #[test]
    fn vocabulary_keeps_words_once_in_order_without_numbers() {
        let words = vocabulary(
            [b"$Nodes 12 x.y\n$Nodes 3.5 abc".as_slice()].into_iter(),
            10,
        );
        assert_eq!(
            words,
            vec![b"$Nodes".to_vec(), b"x.y".to_vec(), b"abc".to_vec()]
        );
    }
}
