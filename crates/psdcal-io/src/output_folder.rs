//! Outputs written under fixed names into a folder (`simulate --out DIR`,
//! `study`, `report`, `simulate-positioning`, the HTML pages of `diff`,
//! `evaluate`, `psd-map` and `plan`) replace only files psdcal wrote there.
//!
//! psdcal keeps a manifest, [`MANIFEST`] (`.psdcal-outputs`), in each folder
//! it writes named outputs into: one line per file it wrote,
//! `name<TAB>bytes<TAB>modified_ns` (the name relative to the folder, the
//! file's length and modification time, in nanoseconds since 1970, right
//! after psdcal wrote it). Before anything is written, every name the run
//! will write is checked ([`OutputFolder::claim`]):
//! - absent: it is written;
//! - listed with the same length and modification time: psdcal wrote it
//!   and nobody changed it since, it is replaced;
//! - anything else (a file psdcal did not write, one edited or touched
//!   since, a folder, a link): the run is refused before any file is
//!   written, with an error naming the file, unless `force` is given.
//!
//! After the writes, [`OutputFolder::finish`] records the files in the
//! manifest (written atomically; other names' lines are kept).
//!
//! Runs into one folder take turns: [`OutputFolder::claim`] creates the
//! folder and holds an exclusive lock on it (`flock` on the folder itself,
//! no lock file) until the [`OutputFolder`] is dropped, so a second run
//! checks its names only once the first has written and recorded its
//! files, and finds them psdcal's. Claims of one folder by one thread share
//! its lock (a run writing two sets of outputs into the same folder); other
//! threads and processes wait, up to 120 s, then get an error.

use std::collections::BTreeMap;
use std::fs::{self, File};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, Weak};
use std::thread::ThreadId;
use std::time::{Duration, Instant, UNIX_EPOCH};

use crate::atomic::write_atomic;
use crate::error::IoError;

/// The manifest's file name.
pub const MANIFEST: &str = ".psdcal-outputs";

/// A manifest larger than this is not psdcal's (it is read as empty).
const MANIFEST_MAX_BYTES: u64 = 4 << 20;

/// How long a run waits for another run writing into the same folder.
pub const LOCK_WAIT: Duration = Duration::from_secs(120);

/// The folder locks this process holds: (folder, thread, lock).
type HeldLocks = Vec<(PathBuf, ThreadId, Weak<File>)>;
static HELD: Mutex<HeldLocks> = Mutex::new(Vec::new());

/// What a manifest line records of a file: its length and modification
/// time (ns since 1970).
type Stamp = (u64, u128);

/// A folder whose named outputs were checked ([`OutputFolder::claim`]) and
/// are recorded once written ([`OutputFolder::finish`]).
#[derive(Debug)]
pub struct OutputFolder {
    dir: PathBuf,
    names: Vec<String>,
    /// The folder's lock, released when the last claim of it is dropped.
    _lock: Arc<File>,
}

impl OutputFolder {
    /// Checks that each of `names` (relative to `dir`, `/`-separated) can be
    /// written into `dir`: it is absent, or psdcal wrote it and it has not
    /// changed since; with `force`, every name can. `dir` is created if
    /// missing and locked (see the module's docs) until the result is
    /// dropped.
    ///
    /// Errors: [`IoError::NotOurs`] naming the first file that would be lost;
    /// [`IoError::Write`] when the folder cannot be created or stays locked
    /// by another run for 120 s.
    pub fn claim(dir: &Path, names: &[String], force: bool) -> Result<OutputFolder, IoError> {
        let folder = OutputFolder {
            dir: dir.to_path_buf(),
            names: names.to_vec(),
            _lock: lock_folder(dir)?,
        };
        if force {
            return Ok(folder);
        }
        let listed = read_manifest(dir);
        for name in names {
            let path = dir.join(name);
            let Ok(meta) = fs::symlink_metadata(&path) else {
                continue;
            };
            let ours = meta.is_file() && listed.get(name) == stamp(&path).as_ref();
            if !ours {
                return Err(IoError::NotOurs {
                    file: path.display().to_string(),
                    message: "exists and psdcal did not write it there (or it changed since), \
                              so it is kept"
                        .to_string(),
                });
            }
        }
        Ok(folder)
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Records the claimed files that now exist in the folder's manifest.
    pub fn finish(self) -> Result<(), IoError> {
        let mut listed = read_manifest(&self.dir);
        for name in &self.names {
            if let Some(s) = stamp(&self.dir.join(name)) {
                listed.insert(name.clone(), s);
            }
        }
        write_atomic(self.dir.join(MANIFEST), |w| {
            writeln!(
                w,
                "# psdcal outputs v1: name, bytes, modified_ns (docs/formats.md)"
            )?;
            for (name, (len, modified)) in &listed {
                writeln!(w, "{name}\t{len}\t{modified}")?;
            }
            Ok(())
        })
    }
}

/// The exclusive lock of `dir` (created if missing): this thread's own if
/// it holds one already, else a new one once no other run holds it.
fn lock_folder(dir: &Path) -> Result<Arc<File>, IoError> {
    let failed = |source: std::io::Error| IoError::Write {
        file: dir.display().to_string(),
        source,
    };
    fs::create_dir_all(dir).map_err(failed)?;
    let key = dir.canonicalize().map_err(failed)?;
    let me = std::thread::current().id();
    let mut held = HELD.lock().unwrap_or_else(|e| e.into_inner());
    held.retain(|(_, _, lock)| lock.strong_count() > 0);
    let mine = held
        .iter()
        .find(|(path, thread, _)| *path == key && *thread == me);
    if let Some(lock) = mine.and_then(|(_, _, lock)| lock.upgrade()) {
        return Ok(lock);
    }
    drop(held);
    let file = File::open(&key).map_err(failed)?;
    let start = Instant::now();
    loop {
        match file.try_lock() {
            Ok(()) => break,
            Err(fs::TryLockError::WouldBlock) if start.elapsed() < LOCK_WAIT => {
                std::thread::sleep(Duration::from_millis(10));
            }
            Err(fs::TryLockError::WouldBlock) => {
                return Err(failed(std::io::Error::other(format!(
                    "another psdcal run has been writing into this folder for {} s",
                    LOCK_WAIT.as_secs()
                ))))
            }
            Err(fs::TryLockError::Error(e)) => return Err(failed(e)),
        }
    }
    let lock = Arc::new(file);
    let mut held = HELD.lock().unwrap_or_else(|e| e.into_inner());
    held.push((key, me, Arc::downgrade(&lock)));
    Ok(lock)
}

/// A file's length and modification time, if it is a file.
fn stamp(path: &Path) -> Option<Stamp> {
    let meta = fs::metadata(path).ok().filter(|m| m.is_file())?;
    let modified = meta.modified().ok()?.duration_since(UNIX_EPOCH).ok()?;
    Some((meta.len(), modified.as_nanos()))
}

/// The folder's manifest (empty when absent or not readable; lines that
/// are not psdcal's are skipped).
fn read_manifest(dir: &Path) -> BTreeMap<String, Stamp> {
    let mut text = String::new();
    let read = fs::File::open(dir.join(MANIFEST))
        .and_then(|f| f.take(MANIFEST_MAX_BYTES).read_to_string(&mut text));
    if read.is_err() {
        return BTreeMap::new();
    }
    text.lines()
        .filter(|l| !l.starts_with('#'))
        .filter_map(|line| {
            let mut fields = line.split('\t');
            let name = fields.next()?.to_string();
            let len = fields.next()?.parse().ok()?;
            let modified = fields.next()?.parse().ok()?;
            Some((name, (len, modified)))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(list: &[&str]) -> Vec<String> {
        list.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn files_psdcal_wrote_are_replaced_and_others_kept() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let outputs = names(&["template.csv", "observations.csv"]);
        // An empty folder: everything can be written.
        let folder = OutputFolder::claim(d, &outputs, false).unwrap();
        fs::write(d.join("template.csv"), "t").unwrap();
        fs::write(d.join("observations.csv"), "o").unwrap();
        folder.finish().unwrap();
        // psdcal's own files: replaced again.
        OutputFolder::claim(d, &outputs, false).unwrap();
        // A file psdcal did not write: refused, named.
        fs::write(d.join("study.csv"), "mine").unwrap();
        let e = OutputFolder::claim(d, &names(&["study.csv"]), false).unwrap_err();
        assert!(matches!(e, IoError::NotOurs { .. }));
        let text = e.to_string();
        assert!(
            text.contains("study.csv") && text.contains("kept"),
            "{text}"
        );
        // A file psdcal wrote but the user edited since: refused too.
        fs::write(d.join("template.csv"), "edited by hand").unwrap();
        assert!(OutputFolder::claim(d, &outputs, false).is_err());
        // --force replaces.
        OutputFolder::claim(d, &outputs, true).unwrap();
        assert_eq!(fs::read(d.join("study.csv")).unwrap(), b"mine");
    }

    #[test]
    fn a_garbled_manifest_protects_everything() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        fs::write(d.join("a.csv"), "a").unwrap();
        fs::write(d.join(MANIFEST), "a.csv\tnot a number\t1\n\u{0}\n").unwrap();
        assert!(OutputFolder::claim(d, &names(&["a.csv"]), false).is_err());
        assert!(OutputFolder::claim(&d.join("absent"), &names(&["a.csv"]), false).is_ok());
    }
}
