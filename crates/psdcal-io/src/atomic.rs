//! Atomic file output: every file psdcal writes (CSV or JSON) appears whole
//! or not at all.
//!
//! The content goes to a new temporary file in the destination's directory
//! (so that the final rename stays on one file system), which is flushed,
//! then renamed over the destination. If anything fails the temporary file is
//! removed and the destination is left as it was.
//!
//! A reader (or psdcal killed mid-write) therefore never sees a partial file.
//! The file is not forced to disk (no `fsync`): on this class of machine an
//! `fsync` costs several milliseconds, more than a whole calibration, and the
//! operating system writes the file back within seconds (file systems such
//! as ext4 flush a file renamed over another before committing the rename).
//! Run `sync` if the power may fail right after a run.
//!
//! Temporary files are named `.<name>.<pid>.<n>.tmp`, or
//! `.<name>.<pid>.<n>.tmp.<ext>` for a writer that tells the format by the
//! extension ([`write_atomic_at`]). A process killed
//! while writing (SIGKILL, power loss) cannot remove its own: the next write
//! into the same folder removes every such file whose process is no longer
//! running (on systems without `/proc`, those older than a day).

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::IoError;

/// Writes a file atomically: `write` fills a buffered temporary file next to
/// `path`, which then replaces `path`.
pub fn write_atomic<F>(path: impl AsRef<Path>, write: F) -> Result<(), IoError>
where
    F: FnOnce(&mut BufWriter<File>) -> io::Result<()>,
{
    let path = path.as_ref();
    let error = |source| IoError::Write {
        file: path.display().to_string(),
        source,
    };
    remove_stale_temps(path);
    let (temp_path, file) = create_temp(path, false).map_err(error)?;
    let result = fill(file, write).and_then(|()| fs::rename(&temp_path, path));
    if let Err(source) = result {
        // Best effort: the temporary file may already be gone.
        let _ = fs::remove_file(&temp_path);
        return Err(error(source));
    }
    Ok(())
}

/// Writes a file atomically with a writer that opens the file itself (a
/// plotting library given a path): `write` writes the temporary file whose
/// path it is given (a fresh, empty file with a name no other writer uses),
/// which then replaces `path`; on failure it is removed and `path` is left as
/// it was. `write`'s error is reported as the write error of `path`.
pub fn write_atomic_at<F, E>(path: impl AsRef<Path>, write: F) -> Result<(), IoError>
where
    F: FnOnce(&Path) -> Result<(), E>,
    E: std::fmt::Display,
{
    let path = path.as_ref();
    let error = |source| IoError::Write {
        file: path.display().to_string(),
        source,
    };
    remove_stale_temps(path);
    let (temp_path, file) = create_temp(path, true).map_err(error)?;
    drop(file);
    let result = write(&temp_path)
        .map_err(|e| io::Error::other(e.to_string()))
        .and_then(|()| fs::rename(&temp_path, path));
    if let Err(source) = result {
        // Best effort: the temporary file may already be gone.
        let _ = fs::remove_file(&temp_path);
        return Err(error(source));
    }
    Ok(())
}

/// Writes `bytes` to `path` atomically. On Linux the temporary file's
/// blocks are allocated before it is written: ext4 flushes a file with
/// delayed-allocation blocks when it is renamed over an existing one, which
/// made that rename take 0.23 ms instead of 0.15 ms for a 9.7 kB file
/// (measured on this machine's ext4); nothing else changes.
pub fn write_atomic_bytes(path: impl AsRef<Path>, bytes: &[u8]) -> Result<(), IoError> {
    write_atomic(path, |w| {
        reserve(w.get_ref(), bytes.len() as u64);
        w.write_all(bytes)
    })
}

/// Allocates `len` bytes of `file` (best effort: a file system without
/// `fallocate` allocates as it writes).
#[cfg(target_os = "linux")]
fn reserve(file: &File, len: u64) {
    if len > 0 {
        let _ = rustix::fs::fallocate(file, rustix::fs::FallocateFlags::empty(), 0, len);
    }
}

#[cfg(not(target_os = "linux"))]
fn reserve(_file: &File, _len: u64) {}

/// A new, exclusively created temporary file in the destination's
/// directory; with `keep_extension`, its name ends in the destination's
/// extension too.
fn create_temp(path: &Path, keep_extension: bool) -> io::Result<(PathBuf, File)> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = path.file_name().ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            "the destination is not a file name",
        )
    })?;
    let dir = match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    };
    loop {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let mut temp_name = std::ffi::OsString::from(".");
        temp_name.push(name);
        temp_name.push(format!(".{}.{n}.tmp", std::process::id()));
        if let Some(ext) = path.extension().filter(|_| keep_extension) {
            temp_name.push(".");
            temp_name.push(ext);
        }
        let temp_path = dir.join(temp_name);
        match OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&temp_path)
        {
            Ok(file) => return Ok((temp_path, file)),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
}

/// The folder a destination is written in.
fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    }
}

/// The process id in a name of psdcal's temporary files
/// (`.<name>.<pid>.<n>.tmp`, optionally followed by `.<ext>`), if the name
/// is one.
fn temp_owner(file_name: &str) -> Option<u32> {
    let inner = file_name.strip_prefix('.')?;
    let inner = match inner.rsplit_once(".tmp.") {
        Some((head, ext)) if !ext.is_empty() && !ext.contains('.') => head,
        _ => inner.strip_suffix(".tmp")?,
    };
    let mut parts = inner.rsplitn(3, '.');
    let n = parts.next()?;
    let pid = parts.next()?;
    let name = parts.next()?;
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    (!name.is_empty() && digits(n) && digits(pid))
        .then(|| pid.parse().ok())
        .flatten()
}

/// Whether the process that owns a temporary file is gone.
fn owner_is_gone(pid: u32, entry: &fs::DirEntry) -> bool {
    if pid == std::process::id() {
        return false;
    }
    let proc = Path::new("/proc");
    if proc.join("self").exists() {
        return !proc.join(pid.to_string()).exists();
    }
    const DAY: std::time::Duration = std::time::Duration::from_secs(24 * 3600);
    entry
        .metadata()
        .and_then(|m| m.modified())
        .ok()
        .and_then(|t| t.elapsed().ok())
        .is_some_and(|age| age > DAY)
}

/// Removes the temporary files left in `path`'s folder by psdcal processes
/// that were killed while writing (best effort).
fn remove_stale_temps(path: &Path) {
    let Ok(entries) = fs::read_dir(folder_of(path)) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(temp_owner) else {
            continue;
        };
        if entry.file_type().is_ok_and(|t| t.is_file()) && owner_is_gone(pid, &entry) {
            let _ = fs::remove_file(entry.path());
        }
    }
}

fn fill<F>(file: File, write: F) -> io::Result<()>
where
    F: FnOnce(&mut BufWriter<File>) -> io::Result<()>,
{
    let mut writer = BufWriter::new(file);
    write(&mut writer)?;
    writer.flush()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn a_writer_given_a_path_writes_atomically_with_the_extension_kept() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("plot.png");
        write_atomic_bytes(&path, b"old").unwrap();
        // The writer sees a fresh temporary file ending in .png.
        write_atomic_at(&path, |tmp: &Path| {
            assert!(tmp.extension().is_some_and(|e| e == "png"), "{tmp:?}");
            let name = tmp.file_name().unwrap().to_str().unwrap();
            assert_eq!(temp_owner(name), Some(std::process::id()));
            fs::write(tmp, b"new")
        })
        .unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"new");
        // A failing writer leaves the destination and no temporary file.
        let err = write_atomic_at(&path, |tmp: &Path| {
            fs::write(tmp, b"partial").unwrap();
            Err("the disk is full")
        })
        .unwrap_err();
        assert!(err.to_string().contains("the disk is full"), "{err}");
        assert_eq!(fs::read(&path).unwrap(), b"new");
        assert_eq!(entries(dir.path()), ["plot.png"]);
    }

    #[test]
    fn temporary_names_with_an_extension_are_recognised_and_others_not() {
        assert_eq!(temp_owner(".coverage.png.42.7.tmp.png"), Some(42));
        assert_eq!(temp_owner(".out.csv.42.7.tmp"), Some(42));
        assert_eq!(temp_owner(".foo.tmp.bar.42.7.tmp"), Some(42));
        assert_eq!(temp_owner(".coverage.png.tmp.png"), None);
        assert_eq!(temp_owner("coverage.png"), None);
    }

    #[test]
    fn writes_and_replaces() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.csv");
        write_atomic_bytes(&path, b"first\n").unwrap();
        assert_eq!(fs::read_to_string(&path).unwrap(), "first\n");
        write_atomic(&path, |w| writeln!(w, "second {}", 2)).unwrap();
        assert_eq!(fs::read_to_string(&path).unwrap(), "second 2\n");
        assert_eq!(entries(dir.path()), ["out.csv"]);
    }

    #[test]
    fn reserved_bytes_replace_a_longer_file_exactly() {
        // The allocation made before writing neither pads nor keeps the
        // old content: the file is the bytes, whatever it replaces.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("calibration.json");
        let long = vec![b'x'; 100_000];
        write_atomic_bytes(&path, &long).unwrap();
        write_atomic_bytes(&path, b"{}\n").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"{}\n");
        write_atomic_bytes(&path, b"").unwrap();
        assert_eq!(fs::metadata(&path).unwrap().len(), 0);
        assert_eq!(entries(dir.path()), ["calibration.json"]);
    }

    #[test]
    fn failure_leaves_destination_untouched_and_no_temp_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.json");
        fs::write(&path, "old").unwrap();
        let e = write_atomic(&path, |w| {
            w.write_all(b"partial new content")?;
            Err(io::Error::other("disk full"))
        })
        .unwrap_err();
        assert_eq!(fs::read_to_string(&path).unwrap(), "old");
        assert_eq!(entries(dir.path()), ["out.json"]);
        assert!(matches!(e, IoError::Write { .. }));
        assert_eq!(
            e.to_string(),
            format!("{}: cannot write the file: disk full", path.display())
        );
    }

    #[test]
    fn stale_temporary_files_of_dead_processes_are_removed() {
        let dir = tempfile::tempdir().unwrap();
        // A process id that cannot be running: beyond Linux's pid_max.
        let dead = dir.path().join(".aoa.csv.4294967295.0.tmp");
        let mine = dir
            .path()
            .join(format!(".aoa.csv.{}.99.tmp", std::process::id()));
        let foreign = dir.path().join(".notes.tmp");
        for p in [&dead, &mine, &foreign] {
            fs::write(p, "partial").unwrap();
        }
        write_atomic_bytes(dir.path().join("other.csv"), b"x").unwrap();
        let mut expected = vec![
            ".notes.tmp".to_string(),
            format!(".aoa.csv.{}.99.tmp", std::process::id()),
            "other.csv".to_string(),
        ];
        if !Path::new("/proc/self").exists() {
            expected.push(".aoa.csv.4294967295.0.tmp".to_string());
        }
        expected.sort();
        assert_eq!(entries(dir.path()), expected);
        assert_eq!(temp_owner(".a.b.csv.12.3.tmp"), Some(12));
        assert_eq!(temp_owner(".12.3.tmp"), None);
        assert_eq!(temp_owner(".a.x2.3.tmp"), None);
    }

    #[test]
    fn missing_directory_is_a_write_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("no/such/dir/out.csv");
        let e = write_atomic_bytes(&path, b"x").unwrap_err();
        assert!(matches!(e, IoError::Write { .. }));
        assert_eq!(entries(dir.path()), Vec::<String>::new());
    }

    #[test]
    fn destination_that_is_a_directory_fails_cleanly() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("sub");
        fs::create_dir(&target).unwrap();
        fs::write(target.join("keep"), "k").unwrap();
        assert!(write_atomic_bytes(&target, b"x").is_err());
        assert_eq!(entries(dir.path()), ["sub"]);
        assert_eq!(entries(&target), ["keep"]);
    }
}
