//! `sweepmtf merge OUT1 OUT2 … -o OUT`: joins the output folders of several
//! batch runs (typically the shards of one job array) into one: per-shot files
//! and markers copied (markers last), summary, pictures and report rebuilt.
//! Shots a folder's plan lists but that have no complete result (a shard
//! stopped early) become error rows, so nothing is silently missing.

use super::manifest::{MANIFEST_FILE, Manifest, ManifestShot};
use super::record::{FailKind, ShotRecord, ShotResult, Status};
use super::resume::{self, Marker};
use super::{BatchError, SHOTS_DIR, atomic};
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

/// What a merge did.
#[derive(Debug, Clone, PartialEq)]
pub struct MergeOutcome {
    /// One record per shot, sorted by file-list position.
    pub records: Vec<ShotRecord>,
    /// Shots planned in some input but without a complete result.
    pub missing: usize,
    /// Report files written.
    pub reports: Vec<PathBuf>,
}

struct Entry {
    shot: ManifestShot,
    from: PathBuf,
    marker: Option<Marker>,
}

fn missing_record(s: &ManifestShot, dir: &Path) -> ShotRecord {
    ShotRecord {
        index: s.index,
        file: s.file.clone(),
        stem: s.stem.clone(),
        status: Status::Error,
        error_kind: Some(FailKind::Output),
        error: Some(format!(
            "no complete result in {} (its run was stopped or is still running; rerun it)",
            dir.display()
        )),
        result: ShotResult::default(),
        run_time_s: 0.0,
    }
}

fn rename_output(name: &str, old: &str, new: &str) -> String {
    match name.strip_prefix(old) {
        Some(rest) if rest.starts_with('.') => format!("{new}{rest}"),
        _ => name.to_string(),
    }
}

/// Merges batch output folders `inputs` into `out`.
pub fn merge(inputs: &[PathBuf], out: &Path) -> Result<MergeOutcome, BatchError> {
    // The output folder is held before anything is read: the inputs may be
    // the output folder itself, which another run may be writing.
    let created = !out.exists();
    std::fs::create_dir_all(out).map_err(|e| BatchError::output(out, e))?;
    let outcome = super::lock::FolderLock::acquire(out).and_then(|lock| {
        let r = merge_held(inputs, out);
        drop(lock);
        r
    });
    // Bad inputs leave no trace: a folder this run created is removed again
    // (`remove_dir` removes only an empty folder, so nothing written is lost).
    if outcome.is_err() && created {
        let _ = std::fs::remove_file(out.join(super::lock::LOCK_FILE));
        let _ = std::fs::remove_dir(out);
    }
    outcome
}

/// [`merge`] with the output folder created and locked.
fn merge_held(inputs: &[PathBuf], out: &Path) -> Result<MergeOutcome, BatchError> {
    let mut entries: Vec<Entry> = Vec::new();
    let mut total = 0;
    for dir in inputs {
        let m = Manifest::read(dir)?;
        total = total.max(m.total_shots);
        let shots_dir = dir.join(SHOTS_DIR);
        for s in m.shots {
            let marker = resume::read_marker(&shots_dir, &s.stem)
                .filter(|mk| mk.record.file == s.file && resume::outputs_present(&shots_dir, mk));
            entries.push(Entry {
                shot: s,
                from: dir.clone(),
                marker,
            });
        }
    }
    // The same shot listed twice (overlapping runs): keep one, preferring a
    // complete ok result, then any complete result.
    let rank = |e: &Entry| match &e.marker {
        Some(m) if m.record.is_ok() => 0,
        Some(_) => 1,
        None => 2,
    };
    entries.sort_by(|a, b| {
        (a.shot.index, &a.shot.file, rank(a)).cmp(&(b.shot.index, &b.shot.file, rank(b)))
    });
    entries.dedup_by(|b, a| a.shot.index == b.shot.index && a.shot.file == b.shot.file);

    // Different shots with the same stem (unrelated runs): later ones renamed.
    let mut taken: HashSet<String> = HashSet::new();
    let mut renames: HashMap<usize, String> = HashMap::new();
    for (i, e) in entries.iter().enumerate() {
        let mut stem = e.shot.stem.clone();
        let mut k = 2;
        while !taken.insert(stem.to_lowercase()) {
            stem = format!("{}-{k}", e.shot.stem);
            k += 1;
        }
        if stem != e.shot.stem {
            renames.insert(i, stem);
        }
    }

    let out_shots = out.join(SHOTS_DIR);
    std::fs::create_dir_all(&out_shots).map_err(|e| BatchError::output(&out_shots, e))?;
    atomic::remove_stale_temps(&out_shots, true).map_err(|e| BatchError::output(&out_shots, e))?;
    let out_canon = std::fs::canonicalize(&out_shots).ok();
    let mut records = Vec::new();
    let mut missing = 0;
    let mut manifest_shots = Vec::new();
    for (i, e) in entries.into_iter().enumerate() {
        let new_stem = renames
            .get(&i)
            .cloned()
            .unwrap_or_else(|| e.shot.stem.clone());
        manifest_shots.push(ManifestShot {
            index: e.shot.index,
            file: e.shot.file.clone(),
            stem: new_stem.clone(),
        });
        let Some(mut marker) = e.marker else {
            missing += 1;
            let mut r = missing_record(&e.shot, &e.from);
            r.stem = new_stem;
            records.push(r);
            continue;
        };
        let src_shots = e.from.join(SHOTS_DIR);
        let same_dir = std::fs::canonicalize(&src_shots).ok() == out_canon;
        let old_stem = marker.record.stem.clone();
        let rec = &mut marker.record;
        rec.stem = new_stem.clone();
        let mut new_outputs = Vec::new();
        for o in &rec.result.outputs {
            let n = rename_output(o, &old_stem, &new_stem);
            if !(same_dir && n == *o) {
                let to = out_shots.join(&n);
                atomic::copy_atomic(&src_shots.join(o), &to)
                    .map_err(|err| BatchError::output(&to, err))?;
            }
            new_outputs.push(n);
        }
        rec.result.outputs = new_outputs;
        rec.result.curve_file = rec
            .result
            .curve_file
            .as_ref()
            .map(|c| rename_output(c, &old_stem, &new_stem));
        if !(same_dir && old_stem == new_stem) {
            resume::write_marker(&out_shots, &marker).map_err(|err| {
                BatchError::output(&resume::marker_path(&out_shots, &new_stem), err)
            })?;
        }
        records.push(marker.record);
    }
    let manifest = Manifest {
        sweepmtf_version: env!("CARGO_PKG_VERSION").to_string(),
        shard: "merged".to_string(),
        total_shots: total.max(records.len()),
        shots: manifest_shots,
    };
    manifest.write(out)?;
    debug_assert!(out.join(MANIFEST_FILE).is_file());
    let title = format!(
        "sweepmtf batch (merged from {} folder{})",
        inputs.len(),
        if inputs.len() == 1 { "" } else { "s" }
    );
    let reports = super::write_reports(out, &records, &title)?;
    Ok(MergeOutcome {
        records,
        missing,
        reports,
    })
}

#[cfg(test)]
mod tests {
    use super::rename_output;

    #[test]
    fn renames_only_the_stem_prefix() {
        assert_eq!(rename_output("x.mtf.csv", "x", "x-2"), "x-2.mtf.csv");
        assert_eq!(rename_output("xy.mtf.csv", "x", "x-2"), "xy.mtf.csv");
    }
}
