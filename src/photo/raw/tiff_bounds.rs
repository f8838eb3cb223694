//! A bounds check of a TIFF-based raw's directory structure before rawler
//! parses it. rawler allocates each directory entry's values from the count
//! the file states (`count × type size` bytes) before reading them, so one
//! damaged count asks for gigabytes; an allocation failure aborts the
//! process and cannot be caught. It also follows its directories without
//! a limit: a chain of directories that loops back never ends, and
//! sub-directories that point back into themselves recurse until the stack
//! overflows. This walk reads only the directories (12 bytes an entry),
//! the ones rawler 0.8 reads and as it finds them (the chain from the
//! header; the SubIFD, EXIF and GPS tags' targets, taken as
//! rawler takes them for each value type, offset 0 included), and refuses
//! an entry whose values could not fit in the file, a loop, or more than
//! [`MAX_IFDS`] directory reads. Offsets that point past the end are left
//! to rawler, which reports them as errors.

use std::collections::{HashMap, HashSet};
use std::io::{Read, Seek, SeekFrom};

/// Directories read at most, counting each time rawler would read one
/// (a directory two pointers lead to counts twice): more is damage.
const MAX_IFDS: usize = 512;

/// Tags whose targets rawler parses as sub-directories (its well-known
/// SubIFDs, EXIF and GPS tags), and the EXIF interoperability directory
/// (not followed by rawler 0.8; walked to be safe). rawler also parses an
/// ICC profile (0x8773) as a directory; its bytes are no directory, so
/// their "counts" say nothing of damage, and it is not walked here.
const POINTER_TAGS: [u16; 4] = [0x014A, 0x8769, 0x8825, 0xA005];

/// Bytes of one value of TIFF field type `t` (1 for unknown types).
fn type_size(t: u16) -> u64 {
    match t {
        3 | 8 => 2,
        4 | 9 | 11 | 13 => 4,
        5 | 10 | 12 | 16..=18 => 8,
        _ => 1,
    }
}

/// Bytes rawler takes a value of type `t` to hold when deciding whether the
/// values sit in the entry itself (unknown types count as bytes).
fn rawler_size(t: u16) -> u64 {
    if unknown_type(t) { 1 } else { type_size(t) }
}

/// Whether rawler reads type `t` as raw bytes of an unknown type.
fn unknown_type(t: u16) -> bool {
    t == 0 || t > 12
}

/// One directory as rawler reads it: where its sub-directories are, and
/// the next directory of the chain (0: none).
struct Dir {
    subs: Vec<u64>,
    next: u64,
}

/// The walk over one file.
struct Walk<'r, R> {
    r: &'r mut R,
    len: u64,
    le: bool,
    /// Directory reads so far (as rawler would make them).
    reads: usize,
    /// Directories read, with their sub-directories' read counts.
    done: HashMap<u64, usize>,
}

impl<R: Read + Seek> Walk<'_, R> {
    fn bytes<const N: usize>(&mut self, at: u64) -> Option<[u8; N]> {
        let mut b = [0u8; N];
        self.r.seek(SeekFrom::Start(at)).ok()?;
        self.r.read_exact(&mut b).ok()?;
        Some(b)
    }

    fn u16_at(&self, b: [u8; 2]) -> u16 {
        if self.le {
            u16::from_le_bytes(b)
        } else {
            u16::from_be_bytes(b)
        }
    }

    fn u32_at(&self, b: [u8; 4]) -> u32 {
        if self.le {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        }
    }

    /// Counts `n` directory reads; too many is damage.
    fn count_reads(&mut self, n: usize) -> Result<(), String> {
        self.reads += n;
        if self.reads > MAX_IFDS {
            return Err(format!("more than {MAX_IFDS} TIFF directories"));
        }
        Ok(())
    }

    /// The directory at `off` (`None` when it cannot be read: rawler
    /// reports that), its entries' sizes checked.
    fn dir(&mut self, off: u64) -> Result<Option<Dir>, String> {
        let Some(n) = self.bytes::<2>(off) else {
            return Ok(None);
        };
        let n = self.u16_at(n) as u64;
        let mut subs = Vec::new();
        // Entry by entry, as rawler reads them: a directory cut off by the
        // end of the file still has its first entries parsed.
        for i in 0..n {
            let at = off + 2 + 12 * i;
            let Some(e) = self.bytes::<12>(at) else {
                return Ok(Some(Dir { subs, next: 0 }));
            };
            let tag = self.u16_at([e[0], e[1]]);
            let typ = self.u16_at([e[2], e[3]]);
            let count = self.u32_at([e[4], e[5], e[6], e[7]]);
            let value = self.u32_at([e[8], e[9], e[10], e[11]]);
            let bytes = count as u64 * type_size(typ);
            if bytes > self.len {
                return Err(format!(
                    "TIFF entry 0x{tag:04X} in the directory at byte {off} claims {count} values \
                     ({bytes} bytes) in a file of {} bytes",
                    self.len
                ));
            }
            if !POINTER_TAGS.contains(&tag) {
                continue;
            }
            // Where rawler finds the values: in the entry when they fit.
            let data = if count as u64 * rawler_size(typ) <= 4 {
                at + 8
            } else {
                value as u64
            };
            match typ {
                // LONG: each value is a directory's offset.
                4 if count == 1 => subs.push(value as u64),
                4 => {
                    if count as usize > MAX_IFDS {
                        return Err(format!(
                            "TIFF entry 0x{tag:04X} in the directory at byte {off} lists {count} \
                             directories (at most {MAX_IFDS} are plausible)"
                        ));
                    }
                    for k in 0..count as u64 {
                        if let Some(p) = self.bytes::<4>(data + 4 * k) {
                            subs.push(self.u32_at(p) as u64);
                        }
                    }
                }
                // UNDEFINED: the values' own place is the directory.
                7 => subs.push(data),
                // Unknown types (IFD = 13 among them): rawler takes the
                // first value byte as the offset.
                t if unknown_type(t) && count > 0 => {
                    if let Some([b]) = self.bytes::<1>(data) {
                        subs.push(b as u64);
                    }
                }
                _ => {}
            }
        }
        let next = self
            .bytes::<4>(off + 2 + 12 * n)
            .map_or(0, |b| self.u32_at(b) as u64);
        Ok(Some(Dir { subs, next }))
    }

    /// The sub-directory at `off` and everything below it; `path` holds the
    /// directories above it (a pointer back into one of them is a loop).
    /// Returns how many directory reads it takes rawler.
    fn sub(&mut self, off: u64, path: &mut Vec<u64>) -> Result<usize, String> {
        if path.contains(&off) {
            return Err(format!(
                "the TIFF directory at byte {off} is its own sub-directory (a loop)"
            ));
        }
        if let Some(&n) = self.done.get(&off) {
            // Read again by rawler, everything below it too.
            self.count_reads(n)?;
            return Ok(n);
        }
        self.count_reads(1)?;
        let Some(d) = self.dir(off)? else {
            return Ok(1);
        };
        path.push(off);
        let mut n = 1;
        for s in d.subs {
            n += self.sub(s, path)?;
        }
        path.pop();
        self.done.insert(off, n);
        Ok(n)
    }
}

/// The first damage of the TIFF in `r` (`len` bytes) that rawler could not
/// survive (an entry whose values cannot fit in the file, directories that
/// loop, too many directories), as a cause for a corrupt-file error; `None`
/// for a sound structure or data that is not TIFF.
pub(crate) fn tiff_damage<R: Read + Seek>(r: &mut R, len: u64) -> Option<String> {
    let mut head = [0u8; 8];
    r.seek(SeekFrom::Start(0)).ok()?;
    r.read_exact(&mut head).ok()?;
    let le = match &head[..4] {
        b"II*\0" => true,
        b"MM\0*" => false,
        _ => return None,
    };
    let mut w = Walk {
        r,
        len,
        le,
        reads: 0,
        done: HashMap::new(),
    };
    let mut next = w.u32_at([head[4], head[5], head[6], head[7]]) as u64;
    let mut chain = HashSet::new();
    let walked = (|| -> Result<(), String> {
        // The chain from the header, each directory with its sub-directories.
        while next != 0 {
            if !chain.insert(next) {
                return Err(format!(
                    "the TIFF's chain of directories loops back to byte {next}"
                ));
            }
            w.count_reads(1)?;
            let Some(d) = w.dir(next)? else {
                break;
            };
            let mut path = vec![next];
            for s in d.subs {
                w.sub(s, &mut path)?;
            }
            next = d.next;
        }
        Ok(())
    })();
    walked.err()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;

    /// A little-endian TIFF: header, one directory with `entries` (tag, type,
    /// count, value), no next directory.
    fn tiff(entries: &[(u16, u16, u32, u32)]) -> Vec<u8> {
        let mut b = b"II*\0".to_vec();
        b.extend(8u32.to_le_bytes());
        b.extend((entries.len() as u16).to_le_bytes());
        for &(tag, typ, count, value) in entries {
            b.extend(tag.to_le_bytes());
            b.extend(typ.to_le_bytes());
            b.extend(count.to_le_bytes());
            b.extend(value.to_le_bytes());
        }
        b.extend(0u32.to_le_bytes());
        b.resize(b.len() + 64, 0);
        b
    }

    fn check(b: &[u8]) -> Option<String> {
        tiff_damage(&mut Cursor::new(b), b.len() as u64)
    }

    #[test]
    fn sound_structures_and_non_tiff_pass() {
        assert_eq!(check(&tiff(&[(256, 4, 1, 640), (257, 4, 1, 480)])), None);
        assert_eq!(check(b"\xFF\xD8\xFF\xE0"), None);
        assert_eq!(check(b""), None);
    }

    #[test]
    fn loops_that_rawler_would_follow_forever_are_refused() {
        // The chain's next pointer back to the first directory (rawler's
        // chain loop never ends).
        let mut b = tiff(&[(256, 4, 1, 640)]);
        b[8 + 2 + 12..8 + 2 + 12 + 4].copy_from_slice(&8u32.to_le_bytes());
        assert!(check(&b).expect("refused").contains("loops back"));
        // A SubIFD pointing at its own directory (rawler recurses).
        assert!(
            check(&tiff(&[(0x014A, 4, 1, 8)]))
                .expect("refused")
                .contains("loop")
        );
        // Shared sub-directories read over and over (each level doubling).
        let mut b = b"II*\0".to_vec();
        b.extend(8u32.to_le_bytes());
        for k in 0..12u32 {
            let here = 8 + 26 * k;
            b.extend(1u16.to_le_bytes());
            b.extend(0x014Au16.to_le_bytes());
            b.extend(4u16.to_le_bytes());
            b.extend(2u32.to_le_bytes());
            b.extend((here + 18).to_le_bytes());
            b.extend(0u32.to_le_bytes());
            b.extend((here + 26).to_le_bytes());
            b.extend((here + 26).to_le_bytes());
        }
        b.extend(0u16.to_le_bytes());
        b.resize(b.len() + 64, 0);
        let w = check(&b).expect("refused");
        assert!(w.contains("more than"), "{w}");
    }

    #[test]
    fn a_sub_directory_at_offset_zero_is_walked_as_rawler_reads_it() {
        // The EXIF pointer set to 0 (found by fuzzing, seed 4816): rawler
        // reads the header as a directory ("II" = 18 761 entries over the
        // file's first bytes), where a value of the real first directory
        // became a count of 4 GB and the allocation aborted the process.
        let mut b = tiff(&[(0x8769, 4, 1, 0), (256, 4, 1, 640), (257, 4, 1, 480)]);
        b.resize(4096, 0);
        // Entry k of the header-as-directory starts at byte 2 + 12k: its
        // count at 6 + 12k. Byte 30 holds the second entry's value (640).
        assert_eq!(6 + 12 * 2, 30);
        b[30..34].copy_from_slice(&u32::MAX.to_le_bytes());
        let w = check(&b).expect("refused");
        assert!(w.contains("directory at byte 0"), "{w}");
        // The same pointer to a sound directory passes.
        let mut c = tiff(&[(0x8769, 4, 1, 40), (256, 4, 1, 640)]);
        c.truncate(40);
        c.extend(&tiff(&[(0x829A, 5, 1, 8)])[8..]);
        assert_eq!(check(&c), None);
    }

    #[test]
    fn real_raws_pass() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/testdata/real");
        let mut n = 0;
        for e in walk(std::path::Path::new(dir)) {
            let ext = e.extension().and_then(|x| x.to_str()).unwrap_or("");
            if [
                "dng", "nef", "cr2", "arw", "orf", "rw2", "pef", "tif", "tiff",
            ]
            .contains(&ext.to_ascii_lowercase().as_str())
            {
                let b = std::fs::read(&e).unwrap();
                assert_eq!(check(&b), None, "{}", e.display());
                n += 1;
            }
        }
        assert!(n > 0, "no TIFF-based raw in testdata/real");
    }

    fn walk(d: &std::path::Path) -> Vec<std::path::PathBuf> {
        let mut out = Vec::new();
        for e in std::fs::read_dir(d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                out.extend(walk(&p));
            } else {
                out.push(p);
            }
        }
        out
    }
}
