//! Unique per-shot output names. A shot's outputs are named after its file
//! stem (`f4.jpg` → `f4.mtf.csv`) unless another shot would get the same
//! name (the same file name in two folders, `x.jpg` beside `x.png`, names
//! differing only in case); those get their relative path with separators
//! replaced (`a/x.jpg` → `a__x`), then the extension (`a__x_jpg`), then a
//! counter. Names are computed over the full, unsharded file list so every
//! shard of a job array agrees on them.

use std::collections::HashMap;

/// Separator replacing `/` in names built from relative paths.
pub const PATH_SEP: &str = "__";

fn sanitize(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_control() || matches!(c, '\\' | ':' | '*' | '?' | '"' | '<' | '>' | '|') {
                '_'
            } else {
                c
            }
        })
        .collect()
}

fn split_ext(path: &str) -> (&str, Option<&str>) {
    let name_start = path.rfind('/').map(|i| i + 1).unwrap_or(0);
    match path[name_start..].rfind('.') {
        Some(i) if i > 0 => (&path[..name_start + i], Some(&path[name_start + i + 1..])),
        _ => (path, None),
    }
}

fn candidate(display: &str, level: u8) -> String {
    let (no_ext, ext) = split_ext(display);
    let name = match level {
        0 => no_ext.rsplit('/').next().unwrap_or(no_ext).to_string(),
        1 => no_ext.replace('/', PATH_SEP),
        _ => match ext {
            Some(e) => format!("{}_{e}", no_ext.replace('/', PATH_SEP)),
            None => no_ext.replace('/', PATH_SEP),
        },
    };
    let name = sanitize(&name);
    if name.is_empty() { "shot".into() } else { name }
}

/// Output stems for shots shown as `displays` (relative paths with `/`),
/// unique even on case-insensitive file systems; same order as the input.
pub fn unique_stems(displays: &[String]) -> Vec<String> {
    let n = displays.len();
    let mut level = vec![0u8; n];
    let mut names: Vec<String> = displays.iter().map(|d| candidate(d, 0)).collect();
    // Raise colliding shots to more specific names until nothing collides or
    // every collider is at the most specific level.
    loop {
        let groups = collisions(&names);
        let mut changed = false;
        for members in groups.values().filter(|m| m.len() > 1) {
            for &i in members {
                if level[i] < 2 {
                    level[i] += 1;
                    names[i] = candidate(&displays[i], level[i]);
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
    // Whatever still collides gets a counter, in file-list order.
    let groups = collisions(&names);
    let mut taken: std::collections::HashSet<String> =
        names.iter().map(|s| s.to_lowercase()).collect();
    let mut keys: Vec<_> = groups.into_iter().filter(|(_, m)| m.len() > 1).collect();
    keys.sort();
    for (_, members) in keys {
        for &i in &members[1..] {
            let mut k = 2;
            loop {
                let cand = format!("{}-{k}", names[i]);
                if taken.insert(cand.to_lowercase()) {
                    names[i] = cand;
                    break;
                }
                k += 1;
            }
        }
    }
    names
}

fn collisions(names: &[String]) -> HashMap<String, Vec<usize>> {
    let mut groups: HashMap<String, Vec<usize>> = HashMap::new();
    for (i, s) in names.iter().enumerate() {
        groups.entry(s.to_lowercase()).or_default().push(i);
    }
    groups
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stems(d: &[&str]) -> Vec<String> {
        unique_stems(&d.iter().map(|s| s.to_string()).collect::<Vec<_>>())
    }

    #[test]
    fn plain_stems_when_unique() {
        assert_eq!(
            stems(&["f4.jpg", "sub/f5.6.jpg", "raw"]),
            ["f4", "f5.6", "raw"]
        );
    }

    #[test]
    fn same_name_in_two_folders_gets_path() {
        assert_eq!(
            stems(&["a/x.jpg", "b/x.jpg", "y.jpg"]),
            ["a__x", "b__x", "y"]
        );
    }

    #[test]
    fn same_stem_different_extension_gets_extension() {
        assert_eq!(stems(&["x.jpg", "x.png"]), ["x_jpg", "x_png"]);
    }

    #[test]
    fn case_only_difference_and_constructed_clash_stay_unique() {
        let s = stems(&["X.JPG", "x.jpg", "a__x.jpg", "a/x.jpg"]);
        let mut lower: Vec<String> = s.iter().map(|n| n.to_lowercase()).collect();
        lower.sort();
        lower.dedup();
        assert_eq!(lower.len(), 4, "{s:?}");
    }

    #[test]
    fn odd_characters_are_replaced() {
        assert_eq!(stems(&["a:b?.jpg"]), ["a_b_"]);
    }
}
