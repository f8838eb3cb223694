//! A bounds check of a TIFF-based raw's directory structure before rawler
//! parses it. rawler allocates each directory entry's values from the count
//! the file states (`count × type size` bytes) before reading them, so one
//! damaged count asks for gigabytes; an allocation failure aborts the
//! process and cannot be caught. This walk reads only the directories
//! (12 bytes an entry) and refuses an entry whose values could not fit in
//! the file. Offsets that point past the end are left to rawler, which
//! reports them as errors.

use std::collections::HashSet;
use std::io::{Read, Seek, SeekFrom};

/// Directories visited at most (IFD chain, SubIFDs, EXIF): more is damage.
const MAX_IFDS: usize = 512;

/// How deep SubIFD and EXIF pointers are followed.
const MAX_DEPTH: usize = 4;

/// Bytes of one value of TIFF field type `t` (1 for unknown types).
fn type_size(t: u16) -> u64 {
    match t {
        3 | 8 => 2,
        4 | 9 | 11 | 13 => 4,
        5 | 10 | 12 | 16..=18 => 8,
        _ => 1,
    }
}

/// The first directory entry of the TIFF in `r` (`len` bytes) whose values
/// cannot fit in the file, as a cause for a corrupt-file error; `None` for
/// a sound structure or data that is not TIFF.
pub(crate) fn tiff_damage<R: Read + Seek>(r: &mut R, len: u64) -> Option<String> {
    let mut head = [0u8; 8];
    r.seek(SeekFrom::Start(0)).ok()?;
    r.read_exact(&mut head).ok()?;
    let le = match &head[..4] {
        b"II*\0" => true,
        b"MM\0*" => false,
        _ => return None,
    };
    let u16_at = |b: &[u8]| {
        let a = [b[0], b[1]];
        if le {
            u16::from_le_bytes(a)
        } else {
            u16::from_be_bytes(a)
        }
    };
    let u32_at = |b: &[u8]| {
        let a = [b[0], b[1], b[2], b[3]];
        if le {
            u32::from_le_bytes(a)
        } else {
            u32::from_be_bytes(a)
        }
    };
    let mut queue = vec![(u32_at(&head[4..]) as u64, 0usize)];
    let mut seen = HashSet::new();
    while let Some((off, depth)) = queue.pop() {
        if off == 0 || !seen.insert(off) {
            continue;
        }
        if seen.len() > MAX_IFDS {
            return Some(format!("more than {MAX_IFDS} TIFF directories"));
        }
        let mut n = [0u8; 2];
        if r.seek(SeekFrom::Start(off)).is_err() || r.read_exact(&mut n).is_err() {
            continue; // past the end: rawler reports it
        }
        let n = u16_at(&n) as usize;
        let mut entries = vec![0u8; 12 * n + 4];
        if r.read_exact(&mut entries).is_err() {
            continue;
        }
        for e in entries[..12 * n].chunks_exact(12) {
            let (tag, typ, count) = (u16_at(&e[0..]), u16_at(&e[2..]), u32_at(&e[4..]));
            let bytes = count as u64 * type_size(typ);
            if bytes > len {
                return Some(format!(
                    "TIFF entry 0x{tag:04X} in the directory at byte {off} claims {count} values \
                     ({bytes} bytes) in a file of {len} bytes"
                ));
            }
            // SubIFDs, EXIF and interoperability directories are followed.
            let pointer = matches!(tag, 0x014A | 0x8769 | 0xA005) && matches!(typ, 4 | 13);
            if pointer && depth < MAX_DEPTH {
                let value = u32_at(&e[8..]) as u64;
                if count == 1 {
                    queue.push((value, depth + 1));
                } else if count > 1 && count <= 64 {
                    let mut list = vec![0u8; 4 * count as usize];
                    if r.seek(SeekFrom::Start(value)).is_ok() && r.read_exact(&mut list).is_ok() {
                        queue.extend(list.chunks_exact(4).map(|p| (u32_at(p) as u64, depth + 1)));
                    }
                }
            }
        }
        queue.push((u32_at(&entries[12 * n..]) as u64, depth));
    }
    None
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
        // A next-directory pointer back to itself ends the walk (no hang).
        let mut b = tiff(&[(256, 4, 1, 640)]);
        b[8 + 2 + 12..8 + 2 + 12 + 4].copy_from_slice(&8u32.to_le_bytes());
        assert_eq!(check(&b), None);
    }

    #[test]
    fn an_entry_larger_than_the_file_is_refused() {
        // 0x7FFFFFFF SHORTs: 4 GB of values in a 100-byte file.
        let w = check(&tiff(&[(273, 3, 0x7FFF_FFFF, 0)])).expect("refused");
        assert!(
            w.contains("0x0111") && w.contains("4294967294 bytes"),
            "{w}"
        );
        // Also inside a SubIFD the first directory points to.
        let mut b = tiff(&[(0x014A, 4, 1, 40)]);
        let sub = tiff(&[(279, 4, 0x4000_0000, 0)]);
        b.truncate(40);
        b.extend(&sub[8..]);
        assert!(check(&b).is_some());
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
