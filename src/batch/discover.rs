//! Finding the shots: every photo (by extension, camera raws included) in the
//! given folders, optionally recursively, in a deterministic order that does
//! not depend on the file system's listing order. The batch's own output
//! folder is never searched, hidden files (`.name`, e.g. macOS `._x.jpg`
//! companions) are skipped, and a file reached twice counts once.

use super::BatchError;
use std::collections::HashSet;
use std::fs;
use std::path::{Path, PathBuf};

/// File extensions (lower case) taken as photos.
pub const PHOTO_EXTENSIONS: &[&str] = &[
    "jpg", "jpeg", "png", "tif", "tiff", "dng", "cr2", "cr3", "nef", "arw", "orf", "rw2", "raf",
    "pef", "srw",
];

/// A photo found in the inputs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FoundShot {
    /// Path to open (as reachable from the current directory).
    pub source: PathBuf,
    /// The path shown to the user, with `/` separators: relative to its input
    /// folder, prefixed by the folder's name when several inputs were given.
    pub display: String,
}

/// Whether `path` has one of the [`PHOTO_EXTENSIONS`] (case-insensitive).
pub fn is_photo(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .map(|e| PHOTO_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str()))
        .unwrap_or(false)
}

fn is_hidden(name: &std::ffi::OsStr) -> bool {
    name.to_string_lossy().starts_with('.')
}

/// Compares paths the way people count: numbers by their value, with a
/// decimal fraction when a `.` sits between digits (`f2` < `f2.8` < `f4` <
/// `f11`, `shot9` < `shot10`), everything else by its bytes; ties (`01`
/// against `1`) fall back to plain text order, so the order is total and
/// deterministic.
pub fn natural_cmp(a: &str, b: &str) -> std::cmp::Ordering {
    use std::cmp::Ordering;
    /// The number starting at `i`: (integer digits without leading zeros,
    /// fraction digits, end index).
    fn number(s: &[u8], mut i: usize) -> (&[u8], &[u8], usize) {
        let start = i;
        while i < s.len() && s[i].is_ascii_digit() {
            i += 1;
        }
        let mut int = &s[start..i];
        while int.len() > 1 && int[0] == b'0' {
            int = &int[1..];
        }
        let mut frac: &[u8] = &[];
        if i + 1 < s.len() && s[i] == b'.' && s[i + 1].is_ascii_digit() {
            let f0 = i + 1;
            i = f0;
            while i < s.len() && s[i].is_ascii_digit() {
                i += 1;
            }
            frac = &s[f0..i];
        }
        (int, frac, i)
    }
    let (ab, bb) = (a.as_bytes(), b.as_bytes());
    let (mut i, mut j) = (0, 0);
    while i < ab.len() && j < bb.len() {
        if ab[i].is_ascii_digit() && bb[j].is_ascii_digit() {
            let (ia, fa, ni) = number(ab, i);
            let (ib, fb, nj) = number(bb, j);
            // Integers by length then digits; fractions digit by digit
            // (a missing digit counts as 0, so 2 < 2.8 and 2.25 < 2.5).
            let o = ia
                .len()
                .cmp(&ib.len())
                .then_with(|| ia.cmp(ib))
                .then_with(|| fa.cmp(fb));
            if o != Ordering::Equal {
                return o;
            }
            i = ni;
            j = nj;
        } else {
            if ab[i] != bb[j] {
                return ab[i].cmp(&bb[j]);
            }
            i += 1;
            j += 1;
        }
    }
    (ab.len() - i).cmp(&(bb.len() - j)).then_with(|| a.cmp(b))
}

/// Finds the photos in `inputs` (folders or single files), searching
/// sub-folders when `recursive`, skipping anything inside `exclude` (the
/// output folder). Order: inputs as given, then paths sorted by their text.
pub fn discover(
    inputs: &[PathBuf],
    recursive: bool,
    exclude: Option<&Path>,
) -> Result<Vec<FoundShot>, BatchError> {
    let exclude = exclude.and_then(|p| fs::canonicalize(p).ok());
    let prefixes = input_prefixes(inputs);
    let mut seen = HashSet::new();
    let mut out = Vec::new();
    for (input, prefix) in inputs.iter().zip(prefixes) {
        let meta = fs::metadata(input).map_err(|e| BatchError::input(input, e))?;
        let mut found: Vec<(String, PathBuf)> = Vec::new();
        if meta.is_file() {
            let name = input
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            found.push((name, input.clone()));
        } else {
            walk(input, "", recursive, exclude.as_deref(), &mut found)?;
            found.sort_by(|a, b| natural_cmp(&a.0, &b.0));
        }
        for (rel, source) in found {
            let key = fs::canonicalize(&source).unwrap_or_else(|_| source.clone());
            if !seen.insert(key) {
                continue;
            }
            let display = match &prefix {
                Some(p) => format!("{p}/{rel}"),
                None => rel,
            };
            out.push(FoundShot { source, display });
        }
    }
    Ok(out)
}

/// The display prefix of each input: none for a single input, else the
/// folder's name, or its path as typed when two inputs share a name.
fn input_prefixes(inputs: &[PathBuf]) -> Vec<Option<String>> {
    if inputs.len() < 2 {
        return vec![None; inputs.len()];
    }
    let names: Vec<String> = inputs
        .iter()
        .map(|p| {
            let c = fs::canonicalize(p).unwrap_or_else(|_| p.clone());
            c.file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_else(|| p.to_string_lossy().into_owned())
        })
        .collect();
    names
        .iter()
        .zip(inputs)
        .map(|(n, p)| {
            if names.iter().filter(|m| *m == n).count() > 1 {
                Some(p.to_string_lossy().trim_end_matches('/').to_string())
            } else {
                Some(n.clone())
            }
        })
        .collect()
}

fn walk(
    dir: &Path,
    rel: &str,
    recursive: bool,
    exclude: Option<&Path>,
    found: &mut Vec<(String, PathBuf)>,
) -> Result<(), BatchError> {
    if let Some(ex) = exclude
        && fs::canonicalize(dir).map(|c| c == ex).unwrap_or(false)
    {
        return Ok(());
    }
    let entries = fs::read_dir(dir).map_err(|e| BatchError::input(dir, e))?;
    for entry in entries {
        let entry = entry.map_err(|e| BatchError::input(dir, e))?;
        let name = entry.file_name();
        if is_hidden(&name) {
            continue;
        }
        let path = entry.path();
        let child_rel = if rel.is_empty() {
            name.to_string_lossy().into_owned()
        } else {
            format!("{rel}/{}", name.to_string_lossy())
        };
        let ftype = entry.file_type().map_err(|e| BatchError::input(&path, e))?;
        if ftype.is_dir() {
            if recursive {
                walk(&path, &child_rel, recursive, exclude, found)?;
            }
        } else if is_photo(&path) {
            // Regular files and symlinks to files (symlinked folders are not
            // followed, so a link loop cannot trap the search).
            if ftype.is_file() || fs::metadata(&path).map(|m| m.is_file()).unwrap_or(false) {
                found.push((child_rel, path));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn touch(p: &Path) {
        fs::create_dir_all(p.parent().unwrap()).unwrap();
        fs::write(p, b"x").unwrap();
    }

    #[test]
    fn finds_photos_by_extension_sorted_and_skips_hidden_and_output() {
        let d = tempfile::tempdir().unwrap();
        let r = d.path();
        for n in [
            "b.JPG",
            "a.png",
            "c.txt",
            ".hidden.jpg",
            "sub/z.nef",
            "sub/a.CR3",
            "out/x.png",
            "d.tiff",
        ] {
            touch(&r.join(n));
        }
        let flat = discover(&[r.to_path_buf()], false, None).unwrap();
        let names: Vec<_> = flat.iter().map(|s| s.display.as_str()).collect();
        assert_eq!(names, ["a.png", "b.JPG", "d.tiff"]);
        let deep = discover(&[r.to_path_buf()], true, Some(&r.join("out"))).unwrap();
        let names: Vec<_> = deep.iter().map(|s| s.display.as_str()).collect();
        assert_eq!(
            names,
            ["a.png", "b.JPG", "d.tiff", "sub/a.CR3", "sub/z.nef"]
        );
    }

    #[test]
    fn several_inputs_get_prefixes_and_duplicates_count_once() {
        let d = tempfile::tempdir().unwrap();
        touch(&d.path().join("one/x.jpg"));
        touch(&d.path().join("two/x.jpg"));
        let inputs = [
            d.path().join("one"),
            d.path().join("two"),
            d.path().join("one/x.jpg"),
        ];
        let found = discover(&inputs, false, None).unwrap();
        let names: Vec<_> = found.iter().map(|s| s.display.as_str()).collect();
        assert_eq!(names, ["one/x.jpg", "two/x.jpg"]);
    }

    #[test]
    fn natural_order_counts_numbers() {
        let mut v = vec![
            "f11.jpg",
            "f2.8.jpg",
            "f4.jpg",
            "f5.6.jpg",
            "shot10.png",
            "shot9.png",
            "shot09.png",
            "a/b.png",
            "a.png",
        ];
        v.sort_by(|a, b| natural_cmp(a, b));
        assert_eq!(
            v,
            [
                "a.png",
                "a/b.png",
                "f2.8.jpg",
                "f4.jpg",
                "f5.6.jpg",
                "f11.jpg",
                "shot09.png",
                "shot9.png",
                "shot10.png"
            ]
        );
    }

    #[test]
    fn missing_input_is_an_error_naming_it() {
        let e = discover(&[PathBuf::from("/no/such/folder")], false, None).unwrap_err();
        assert!(e.to_string().contains("/no/such/folder"), "{e}");
    }
}
