//! Writing outputs so that nothing the user had is lost or mixed:
//!
//! - only regular files are written: an existing symlink, FIFO, device or
//!   folder at an output path is refused (never read, never replaced);
//! - every file is written to a temporary file beside it, then renamed, so a
//!   reader sees the old or the new content, never a torn one;
//! - the files of one compile are renamed as a set under a lock on their
//!   folder, so two concurrent compiles never leave a mixed set;
//! - temporary files left by a killed run are removed by the next one;
//! - a file whose content is unchanged is not rewritten.

use std::fs::{self, File, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// The lock file in an output folder.
const LOCK_NAME: &str = ".tsfc.lock";
/// Marks tsfc's temporary files: `.<name>.tsfc-tmp.<pid>.<n>`.
const TMP_MARK: &str = ".tsfc-tmp.";

/// Numbers the temporary files of this process.
static TMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Whether `path` may be written: absent, or an existing regular file (a
/// symlink is refused even when it points to one).
pub fn check_target(path: &Path) -> io::Result<()> {
    match fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_file() => Ok(()),
        Ok(m) => {
            let what = if m.file_type().is_symlink() {
                "a symbolic link"
            } else if m.is_dir() {
                "a folder"
            } else {
                "not a regular file (a device, FIFO or socket)"
            };
            Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "refusing to write `{}`: it is {what}; outputs are regular files only",
                    path.display()
                ),
            ))
        }
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(e),
    }
}

/// Whether the regular file at `path` already holds exactly `bytes`.
fn unchanged(path: &Path, bytes: &[u8]) -> bool {
    fs::symlink_metadata(path).is_ok_and(|m| m.is_file() && m.len() == bytes.len() as u64)
        && fs::read(path).is_ok_and(|old| old == bytes)
}

fn folder_of(path: &Path) -> &Path {
    path.parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into())
}

/// Whether process `pid` is running (unknown elsewhere than Linux: assume yes).
fn alive(pid: u32) -> bool {
    if cfg!(target_os = "linux") {
        Path::new("/proc").join(pid.to_string()).exists()
    } else {
        true
    }
}

/// Removes the temporary files of `name` left in `dir` by runs that died.
fn remove_stale_temps(dir: &Path, name: &str) {
    let prefix = format!(".{name}{TMP_MARK}");
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let n = e.file_name().to_string_lossy().into_owned();
        let Some(rest) = n.strip_prefix(&prefix) else {
            continue;
        };
        let pid = rest.split('.').next().and_then(|p| p.parse::<u32>().ok());
        if pid.is_some_and(|p| p != std::process::id() && !alive(p)) {
            let _ = fs::remove_file(e.path());
        }
    }
}

/// Writes `bytes` to a new temporary file beside `path`.
fn write_temp(path: &Path, bytes: &[u8]) -> io::Result<PathBuf> {
    let n = TMP_COUNTER.fetch_add(1, Ordering::Relaxed);
    let tmp = folder_of(path).join(format!(
        ".{}{TMP_MARK}{}.{n}",
        file_name(path),
        std::process::id()
    ));
    let mut f = OpenOptions::new().write(true).create_new(true).open(&tmp)?;
    f.write_all(bytes)
        .and_then(|()| f.sync_all())
        .inspect_err(|_| {
            let _ = fs::remove_file(&tmp);
        })?;
    Ok(tmp)
}

/// Writes a set of files (each `(path, bytes)`) atomically and together:
/// every target is checked first, every content goes to a temporary file,
/// then all are renamed under the folder's lock. On any failure no target is
/// replaced by a partial content and the temporary files are removed.
pub fn write_set(files: &[(PathBuf, Vec<u8>)]) -> io::Result<()> {
    for (path, _) in files {
        check_target(path)?;
    }
    let todo: Vec<&(PathBuf, Vec<u8>)> = files.iter().filter(|(p, b)| !unchanged(p, b)).collect();
    if todo.is_empty() {
        return Ok(());
    }
    let mut temps = Vec::new();
    let cleanup = |temps: &[(PathBuf, &PathBuf, &[u8])]| {
        for (t, _, _) in temps {
            let _ = fs::remove_file(t);
        }
    };
    for (path, bytes) in files {
        fs::create_dir_all(folder_of(path))?;
        match write_temp(path, bytes) {
            Ok(t) => temps.push((t, path, bytes.as_slice())),
            Err(e) => {
                cleanup(&temps);
                return Err(e);
            }
        }
    }
    let result = rename_locked(&temps);
    if result.is_err() {
        cleanup(&temps);
    }
    result
}

/// Renames every `(temp, target, bytes)` while holding the lock of the first
/// target's folder (files of one compile share a folder). Whether a target
/// already holds its bytes is decided under the lock too, so a concurrent
/// writer cannot slip in between the comparison and the renames.
fn rename_locked(temps: &[(PathBuf, &PathBuf, &[u8])]) -> io::Result<()> {
    let Some((_, first, _)) = temps.first() else {
        return Ok(());
    };
    let dir = folder_of(first);
    let lock = File::options()
        .create(true)
        .truncate(false)
        .write(true)
        .open(dir.join(LOCK_NAME))?;
    lock.lock()?;
    let mut result = Ok(());
    for (tmp, target, bytes) in temps {
        if unchanged(target, bytes) {
            let _ = fs::remove_file(tmp);
            continue;
        }
        // A target may have become a non-regular file since the first check.
        if let Err(e) = check_target(target).and_then(|()| fs::rename(tmp, target)) {
            result = Err(e);
            break;
        }
    }
    for (_, target, _) in temps {
        remove_stale_temps(folder_of(target), &file_name(target));
    }
    let _ = lock.unlock();
    result
}

/// Writes one file as [`write_set`] does.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    write_set(&[(path.to_path_buf(), bytes.to_vec())])
}

/// Rewrites the user's own file at `path` (a spec `tsfc fmt` formats): the
/// new content goes to a temporary file beside it, which takes the file's
/// permissions and is renamed over it. No lock file is left in the user's
/// folder (one file, not a set); an unchanged content is not rewritten.
pub fn replace_file(path: &Path, bytes: &[u8]) -> io::Result<()> {
    check_target(path)?;
    if unchanged(path, bytes) {
        return Ok(());
    }
    let permissions = fs::metadata(path).ok().map(|m| m.permissions());
    let tmp = write_temp(path, bytes)?;
    let renamed = permissions
        .map_or(Ok(()), |p| fs::set_permissions(&tmp, p))
        .and_then(|()| fs::rename(&tmp, path));
    if renamed.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    remove_stale_temps(folder_of(path), &file_name(path));
    renamed
}

/// The largest spec file read, in bytes.
pub const MAX_SPEC_BYTES: u64 = 4 << 20;

/// Reads a spec file of at most [`MAX_SPEC_BYTES`] (a FIFO or device is read
/// up to that limit, never further).
pub fn read_limited(path: &Path) -> io::Result<Vec<u8>> {
    use std::io::Read;
    let f = File::open(path)?;
    if f.metadata()?.is_dir() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            "it is a folder, not a spec file",
        ));
    }
    let mut bytes = Vec::new();
    f.take(MAX_SPEC_BYTES + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > MAX_SPEC_BYTES {
        return Err(io::Error::new(
            io::ErrorKind::InvalidData,
            format!(
                "the spec is larger than the limit of {} MiB",
                MAX_SPEC_BYTES >> 20
            ),
        ));
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("tsfc-output-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).expect("scratch folder"); // ok: unit test
        d
    }

    #[test]
    fn a_set_replaces_regular_files_and_leaves_no_temporaries() {
        let d = scratch("set");
        let (a, b) = (d.join("a.c"), d.join("a.h"));
        fs::write(&a, "old").expect("write"); // ok: unit test
        write_set(&[
            (a.clone(), b"new a".to_vec()),
            (b.clone(), b"new h".to_vec()),
        ])
        .expect("written"); // ok: unit test
        assert_eq!(fs::read(&a).expect("a"), b"new a"); // ok: unit test
        assert_eq!(fs::read(&b).expect("b"), b"new h"); // ok: unit test
        let names: Vec<String> = fs::read_dir(&d)
            .expect("list") // ok: unit test
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        assert!(!names.iter().any(|n| n.contains(TMP_MARK)), "{names:?}");
        let _ = fs::remove_dir_all(&d);
    }

    #[cfg(unix)]
    #[test]
    fn symlinks_and_devices_are_refused_and_left_alone() {
        let d = scratch("special");
        let real = d.join("real.json");
        fs::write(&real, "keep").expect("write"); // ok: unit test
        let link = d.join("link.json");
        std::os::unix::fs::symlink(&real, &link).expect("symlink"); // ok: unit test
        let e = write_atomic(&link, b"x").expect_err("symlink refused");
        assert!(e.to_string().contains("symbolic link"), "{e}");
        assert!(fs::symlink_metadata(&link)
            .expect("still there") // ok: unit test
            .file_type()
            .is_symlink());
        assert_eq!(fs::read(&real).expect("target"), b"keep"); // ok: unit test
        let e = write_atomic(Path::new("/dev/null"), b"x").expect_err("device refused");
        assert!(e.to_string().contains("not a regular file"), "{e}");
        let e = write_atomic(&d, b"x").expect_err("folder refused");
        assert!(e.to_string().contains("folder"), "{e}");
        let _ = fs::remove_dir_all(&d);
    }

    #[test]
    fn stale_temporaries_of_dead_runs_are_removed() {
        let d = scratch("stale");
        let target = d.join("c.rs");
        // PID 0 never names a user process: its file counts as left by a dead run.
        let stale = d.join(format!(".c.rs{TMP_MARK}0.7"));
        fs::write(&stale, "partial").expect("write"); // ok: unit test
        write_atomic(&target, b"fn main() {}").expect("written"); // ok: unit test
        if cfg!(target_os = "linux") {
            assert!(!stale.exists(), "stale temporary removed");
        }
        let _ = fs::remove_dir_all(&d);
    }

    #[cfg(unix)]
    #[test]
    fn reading_is_bounded() {
        let e = read_limited(Path::new("/dev/zero")).expect_err("endless input refused");
        assert!(e.to_string().contains("larger than the limit"), "{e}");
    }
}
