//! Joins the reports of a sharded audit (`--shard K/N`) into the report one unsharded run
//! gives: the same files and materials in the same order, counts and verdict. Shards are
//! refused unless they are every shard of one run: same gloffuse, Blender, settings and
//! inputs, each shard once, each holding exactly the files the split gives it.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use super::shard_cost::file_costs;
use super::verdict::{AuditReport, AuditedFile, ShardRun};
use crate::plural::count;
use crate::shard::{assign, in_order};
use crate::{Error, Field, Hint};

/// A merged report, and where each of its materials came from.
pub struct Merged {
    pub report: AuditReport,
    /// Per material, in the merged order: the shard (from 0) and the material's index in
    /// that shard's report (which names its picture there).
    pub sources: Vec<(usize, usize)>,
    /// The shards' paths, in shard order.
    pub shards: Vec<PathBuf>,
}

/// A shard's report.json: the path itself, or `report.json` inside a `--report` folder.
pub fn report_json(path: &Path) -> PathBuf {
    if path.is_dir() {
        path.join("report.json")
    } else {
        path.to_path_buf()
    }
}

/// Reads the audit report at `path` (a report.json, or the folder holding one).
fn read_report(path: &Path) -> Result<AuditReport, Error> {
    let json = report_json(path);
    let text = read_regular(&json)?;
    serde_json::from_str(&text).map_err(|e| {
        Error::input(
            Field::ShardReport,
            json.display(),
            Hint::new(
                format!("an audit report of a shard ({{}} K/N): {e}"),
                [Field::Shard],
            ),
        )
    })
}

/// The text of `path`, a regular file (or a link to one). A shard's folder is on storage
/// others write: a FIFO or a device there is refused, and opened without blocking, so one
/// put in place between the check and the open is refused too rather than hanging the merge.
fn read_regular(path: &Path) -> Result<String, Error> {
    use std::io::Read;
    use std::os::unix::fs::OpenOptionsExt;
    let read_error = |source| Error::Read {
        path: path.to_path_buf(),
        source,
    };
    let not_regular = || {
        Error::input(
            Field::ShardReport,
            path.display(),
            "a regular file (a shard's report.json), not a FIFO, device, socket or folder",
        )
    };
    if !std::fs::metadata(path).map_err(read_error)?.is_file() {
        return Err(not_regular());
    }
    let mut file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)
        .map_err(read_error)?;
    if !file.metadata().map_err(read_error)?.is_file() {
        return Err(not_regular());
    }
    let mut text = String::new();
    file.read_to_string(&mut text).map_err(read_error)?;
    Ok(text)
}

/// Reads and merges every shard of one run, given in any order (each a report.json or the
/// folder holding one).
pub fn merge(paths: &[PathBuf]) -> Result<Merged, Error> {
    let shards = paths
        .iter()
        .map(|path| {
            let r = read_report(path)?;
            Ok((path.clone(), r.shard.as_ref().map(|s| s.shard), r))
        })
        .collect::<Result<Vec<_>, Error>>()?;
    let ordered = in_order(shards)?;
    let (first_path, first) = &ordered[0];
    for (path, r) in &ordered[1..] {
        if let Some(what) = difference(first, r) {
            return Err(Error::input(
                Field::ShardReport,
                path.display(),
                format!(
                    "a shard of the same run as {}: {what}",
                    first_path.display()
                ),
            ));
        }
    }
    let run = first.shard.clone().expect("in_order checked every shard");
    let materials: Vec<usize> = run.inputs.iter().map(|i| i.materials).collect();
    let owner = assign(&file_costs(&materials), run.shard.count);
    for (k, (path, r)) in ordered.iter().enumerate() {
        check_part(path, r, &run, &owner, k)?;
    }
    let mut report = AuditReport {
        shard: None,
        files: Vec::new(),
        materials: Vec::new(),
        ..first.clone()
    };
    // Each shard's files and materials by file name, found once rather than searched for
    // every input.
    let by_file: Vec<HashMap<&str, (&AuditedFile, Vec<usize>)>> = ordered
        .iter()
        .map(|(_, r)| {
            let mut files: HashMap<&str, (&AuditedFile, Vec<usize>)> = r
                .files
                .iter()
                .map(|f| (f.file.as_str(), (f, Vec::new())))
                .collect();
            for (i, m) in r.materials.iter().enumerate() {
                if let Some((_, indices)) = files.get_mut(m.file.as_str()) {
                    indices.push(i);
                }
            }
            files
        })
        .collect();
    let mut sources = Vec::new();
    for (input, &k) in run.inputs.iter().zip(&owner) {
        let Some((file, indices)) = by_file[k].get(input.file.as_str()) else {
            continue;
        };
        report.files.push((*file).clone());
        for &i in indices {
            report.materials.push(ordered[k].1.materials[i].clone());
            sources.push((k, i));
        }
    }
    // Each shard names the baseline's materials gone from its own files.
    if let Some(summary) = &mut report.baseline {
        summary.absent = ordered
            .iter()
            .filter_map(|(_, r)| r.baseline.as_ref())
            .flat_map(|b| b.absent.iter().cloned())
            .collect();
        summary.absent.sort();
        summary.absent.dedup();
    }
    report.finish();
    Ok(Merged {
        report,
        sources,
        shards: ordered.into_iter().map(|(p, _)| p).collect(),
    })
}

/// What makes `r` a shard of another run than `first`, in words.
fn difference(first: &AuditReport, r: &AuditReport) -> Option<String> {
    let (a, b) = (&first.shard.as_ref()?.inputs, &r.shard.as_ref()?.inputs);
    if r.gloffuse_version != first.gloffuse_version {
        return Some(format!(
            "it was made by gloffuse {}, the other by {}",
            r.gloffuse_version, first.gloffuse_version
        ));
    }
    if r.blender_version != first.blender_version {
        return Some(format!(
            "it ran Blender {}, the other {}",
            r.blender_version, first.blender_version
        ));
    }
    if r.settings != first.settings {
        return Some(format!(
            "its settings differ ({})",
            serde_json::to_string(&r.settings).unwrap_or_default()
        ));
    }
    let baseline = |r: &AuditReport| r.baseline.as_ref().map(|b| b.path.clone());
    if baseline(r) != baseline(first) {
        return Some(format!(
            "it was compared with another baseline ({}, the other {})",
            baseline(r).unwrap_or_else(|| "none".into()),
            baseline(first).unwrap_or_else(|| "none".into())
        ));
    }
    if b != a {
        return Some(format!(
            "its input files differ ({}, the other {}, or their names or material counts)",
            count(b.len(), "file", "files"),
            a.len()
        ));
    }
    None
}

/// Checks that shard `k` (from 0) holds exactly the files the split gives it.
fn check_part(
    path: &Path,
    r: &AuditReport,
    run: &ShardRun,
    owner: &[usize],
    k: usize,
) -> Result<(), Error> {
    let expected: Vec<&str> = run
        .inputs
        .iter()
        .zip(owner)
        .filter(|(_, o)| **o == k)
        .map(|(i, _)| i.file.as_str())
        .collect();
    let held: Vec<&str> = r.files.iter().map(|f| f.file.as_str()).collect();
    if held == expected
        && r.materials
            .iter()
            .all(|m| expected.contains(&m.file.as_str()))
    {
        return Ok(());
    }
    Err(Error::input(
        Field::ShardReport,
        path.display(),
        format!(
            "shard {}'s own files as the split gives them ({}); it holds {}, not all of \
             them its own: was it edited, or made by another gloffuse?",
            k + 1,
            count(expected.len(), "file", "files"),
            count(held.len(), "file", "files")
        ),
    ))
}
