//! Mutations of valid files: bit flips, byte overwrites, truncation, splices,
//! and format-aware ones (segment, chunk and IFD length/offset fields set to
//! edge values; image dimensions made huge or zero); for text files, numbers
//! replaced by extreme values and lines deleted, doubled or swapped.

/// A small deterministic generator (SplitMix64), so a case is reproducible from its number.
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    /// A generator for case `i` of run `seed`.
    pub fn new(seed: u64, i: u64) -> Rng {
        let mut r = Rng(seed ^ i.wrapping_mul(0x9E37_79B9_7F4A_7C15));
        r.next_u64();
        r
    }
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// A number in `0..n` (`n` > 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }
    /// One element of `items`.
    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// Edge values written into 16- and 32-bit fields.
const EDGE32: [u32; 10] = [
    0,
    1,
    2,
    0x7F,
    0xFFFF,
    0x1_0000,
    0x7FFF_FFFF,
    0x8000_0000,
    0xFFFF_FFFE,
    0xFFFF_FFFF,
];

/// Which binary layout a file has (for the format-aware mutations).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    /// JPEG segments.
    Jpeg,
    /// PNG chunks.
    Png,
    /// TIFF/DNG IFDs.
    Tiff,
}

/// A field to mutate: its offset, width in bytes, big-endian or not, and whether it is a dimension.
#[derive(Debug, Clone, Copy)]
struct Field {
    at: usize,
    width: usize,
    big: bool,
    dimension: bool,
}

fn put(bytes: &mut [u8], f: Field, v: u32) {
    let b = if f.big {
        v.to_be_bytes()
    } else {
        v.to_le_bytes()
    };
    if f.at + f.width > bytes.len() {
        return;
    }
    if f.width == 2 {
        let h = if f.big {
            (v as u16).to_be_bytes()
        } else {
            (v as u16).to_le_bytes()
        };
        bytes[f.at..f.at + 2].copy_from_slice(&h);
    } else {
        bytes[f.at..f.at + 4].copy_from_slice(&b);
    }
}

/// The length/offset/dimension fields of a file.
fn fields(bytes: &[u8], layout: Layout) -> Vec<Field> {
    let mut out = Vec::new();
    match layout {
        Layout::Jpeg => {
            let mut i = 2;
            while i + 4 <= bytes.len() && bytes[i] == 0xFF {
                let m = bytes[i + 1];
                if m == 0xD9 || (0xD0..=0xD7).contains(&m) {
                    break;
                }
                let len = u16::from_be_bytes([bytes[i + 2], bytes[i + 3]]) as usize;
                out.push(Field {
                    at: i + 2,
                    width: 2,
                    big: true,
                    dimension: false,
                });
                if matches!(m, 0xC0..=0xC3) {
                    for at in [i + 5, i + 7] {
                        out.push(Field {
                            at,
                            width: 2,
                            big: true,
                            dimension: true,
                        });
                    }
                }
                if m == 0xDA {
                    break;
                }
                i += 2 + len.max(2);
            }
        }
        Layout::Png => {
            let mut i = 8;
            while i + 8 <= bytes.len() {
                let len = u32::from_be_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
                out.push(Field {
                    at: i,
                    width: 4,
                    big: true,
                    dimension: false,
                });
                if &bytes[i + 4..i + 8] == b"IHDR" {
                    for at in [i + 8, i + 12] {
                        out.push(Field {
                            at,
                            width: 4,
                            big: true,
                            dimension: true,
                        });
                    }
                }
                i += 12 + len as usize;
            }
        }
        Layout::Tiff => {
            if bytes.len() < 8 {
                return out;
            }
            let big = &bytes[..2] == b"MM";
            let u16_at = |p: usize| {
                let b = [bytes[p], bytes[p + 1]];
                if big {
                    u16::from_be_bytes(b)
                } else {
                    u16::from_le_bytes(b)
                }
            };
            let u32_at = |p: usize| {
                let b = [bytes[p], bytes[p + 1], bytes[p + 2], bytes[p + 3]];
                if big {
                    u32::from_be_bytes(b)
                } else {
                    u32::from_le_bytes(b)
                }
            };
            let mut ifds = vec![u32_at(4) as usize];
            let mut seen = 0;
            while let Some(ifd) = ifds.pop() {
                seen += 1;
                if seen > 16 || ifd + 2 > bytes.len() {
                    continue;
                }
                let n = u16_at(ifd) as usize;
                out.push(Field {
                    at: ifd,
                    width: 2,
                    big,
                    dimension: false,
                });
                for k in 0..n.min(200) {
                    let e = ifd + 2 + 12 * k;
                    if e + 12 > bytes.len() {
                        break;
                    }
                    let tag = u16_at(e);
                    out.push(Field {
                        at: e + 4,
                        width: 4,
                        big,
                        dimension: false,
                    });
                    out.push(Field {
                        at: e + 8,
                        width: 4,
                        big,
                        dimension: matches!(tag, 256 | 257 | 322 | 323 | 50829),
                    });
                    if tag == 330 || tag == 34665 {
                        ifds.push(u32_at(e + 8) as usize);
                    }
                }
                let next = ifd + 2 + 12 * n;
                if next + 4 <= bytes.len() {
                    let nx = u32_at(next) as usize;
                    if nx != 0 {
                        ifds.push(nx);
                    }
                }
            }
        }
    }
    out
}

/// Mutates a binary file in place with 1–3 random mutations; returns what was done.
pub fn mutate_binary(bytes: &mut Vec<u8>, layout: Layout, rng: &mut Rng) -> String {
    let mut what = Vec::new();
    let rounds = 1 + rng.below(3);
    for _ in 0..rounds {
        if bytes.is_empty() {
            break;
        }
        let n = bytes.len();
        match rng.below(8) {
            0 | 1 => {
                let k = 1 + rng.below(8);
                for _ in 0..k {
                    let p = rng.below(n);
                    bytes[p] ^= 1 << rng.below(8);
                }
                what.push(format!("flip {k} bits"));
            }
            2 => {
                let p = rng.below(n);
                let k = (1 + rng.below(64)).min(n - p);
                let v = *rng.pick(&[0u8, 0xFF, 0x7F, 0x80]);
                let random = rng.below(2) == 0;
                for b in &mut bytes[p..p + k] {
                    *b = if random { rng.next_u64() as u8 } else { v };
                }
                what.push(format!("overwrite {k} bytes at {p}"));
            }
            3 => {
                let p = rng.below(n);
                bytes.truncate(p);
                what.push(format!("truncate at {p}"));
            }
            4 => {
                // Copy a block over another place (repeats structure, breaks offsets).
                let a = rng.below(n);
                let k = (1 + rng.below(512)).min(n - a);
                let block = bytes[a..a + k].to_vec();
                let b = rng.below(n);
                let end = (b + k).min(n);
                bytes[b..end].copy_from_slice(&block[..end - b]);
                what.push(format!("splice {k} bytes {a}->{b}"));
            }
            5 | 6 => {
                let fs = fields(bytes, layout);
                if fs.is_empty() {
                    continue;
                }
                let f = *rng.pick(&fs);
                let v = if rng.below(3) == 0 {
                    rng.next_u64() as u32
                } else {
                    *rng.pick(&EDGE32)
                };
                put(bytes, f, v);
                what.push(format!("field at {} := {v:#x}", f.at));
            }
            _ => {
                let fs: Vec<Field> = fields(bytes, layout)
                    .into_iter()
                    .filter(|f| f.dimension)
                    .collect();
                if fs.is_empty() {
                    continue;
                }
                let f = *rng.pick(&fs);
                let v = *rng.pick(&[0u32, 1, 3, 65_500, 65_535, 100_000, 1 << 20, 0x7FFF_FFFF]);
                put(bytes, f, v);
                what.push(format!("dimension at {} := {v}", f.at));
            }
        }
    }
    what.join(", ")
}

/// Extreme values written over numbers in text files.
const EXTREMES: [&str; 14] = [
    "0",
    "-1",
    "-0.0",
    "1e308",
    "-1e308",
    "1e-308",
    "nan",
    "inf",
    "-inf",
    "18446744073709551616",
    "4294967295",
    "1e9",
    "0.000001",
    "\"x\"",
];

/// Mutates a text file (TOML or sineMTF) with 1–3 random mutations; returns what was done.
pub fn mutate_text(text: &mut String, rng: &mut Rng) -> String {
    let mut what = Vec::new();
    for _ in 0..1 + rng.below(3) {
        let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
        if lines.is_empty() {
            break;
        }
        match rng.below(7) {
            0..=2 => {
                // Replace one number.
                let spans = number_spans(text);
                if spans.is_empty() {
                    continue;
                }
                let (a, b) = *rng.pick(&spans);
                let v = *rng.pick(&EXTREMES);
                what.push(format!("number {} -> {v}", &text[a..b]));
                text.replace_range(a..b, v);
                continue;
            }
            3 => {
                let i = rng.below(lines.len());
                what.push(format!("delete line {i}"));
                lines.remove(i);
            }
            4 => {
                let i = rng.below(lines.len());
                let k = 1 + rng.below(200);
                what.push(format!("repeat line {i} x{k}"));
                let l = lines[i].clone();
                for _ in 0..k {
                    lines.insert(i, l.clone());
                }
            }
            5 => {
                let (i, j) = (rng.below(lines.len()), rng.below(lines.len()));
                what.push(format!("swap lines {i},{j}"));
                lines.swap(i, j);
            }
            _ => {
                let mut b = std::mem::take(text).into_bytes();
                let p = rng.below(b.len().max(1));
                if rng.below(2) == 0 {
                    b.truncate(p);
                    what.push(format!("truncate at {p}"));
                } else if !b.is_empty() {
                    b[p] ^= 1 << rng.below(7);
                    what.push(format!("flip a bit at {p}"));
                }
                *text = String::from_utf8_lossy(&b).into_owned();
                continue;
            }
        }
        *text = lines.join("\n");
        text.push('\n');
    }
    what.join(", ")
}

/// Byte spans of the numbers in `text`.
fn number_spans(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let starts =
            b[i].is_ascii_digit() || (b[i] == b'-' && b.get(i + 1).is_some_and(u8::is_ascii_digit));
        let boundary = i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_');
        if starts && boundary {
            let a = i;
            i += 1;
            while i < b.len()
                && (b[i].is_ascii_digit() || matches!(b[i], b'.' | b'e' | b'E' | b'-' | b'+'))
            {
                i += 1;
            }
            out.push((a, i));
        } else {
            i += 1;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_case_same_mutation() {
        let base: Vec<u8> = (0..=255u8).cycle().take(4096).collect();
        let run = |i| {
            let mut b = base.clone();
            let w = mutate_binary(&mut b, Layout::Jpeg, &mut Rng::new(7, i));
            (b, w)
        };
        assert_eq!(run(3), run(3));
        assert_ne!(run(3).0, run(4).0);
        let mut t = "a = 1.5\nb = [2, 3]\n".to_string();
        mutate_text(&mut t, &mut Rng::new(1, 1));
        assert_eq!(number_spans("x1 = -2.5e3, 7"), vec![(5, 11), (13, 14)]);
    }
}
