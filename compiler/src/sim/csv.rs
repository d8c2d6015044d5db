//! The CSV trace, streamed to disk while the loop runs: `t, <states>,
//! <inputs>, transmitted` (and `mode`, the index of the Markov mode, for a
//! spec with `modes`), one row per sampling instant, numbers in Rust's
//! shortest round-trip format (deterministic text). The file is written
//! atomically: rows go to a temporary file in the target folder, renamed over
//! the target only when the run has finished; on failure the temporary file
//! is removed and an existing target is left as it was.

use std::fs::{File, OpenOptions};
use std::io::{self, BufWriter, Read, Write};
use std::path::{Path, PathBuf};

/// Writes the header line.
pub fn header(
    out: &mut dyn Write,
    state_names: &[String],
    input_names: &[String],
    mode: bool,
) -> io::Result<()> {
    out.write_all(b"t")?;
    for name in state_names.iter().chain(input_names) {
        write!(out, ",{name}")?;
    }
    out.write_all(if mode {
        b",transmitted,mode\n".as_slice()
    } else {
        b",transmitted\n".as_slice()
    })
}

/// Writes one number (shortest round-trip digits; see the module notes).
pub fn number(out: &mut dyn Write, v: f64) -> io::Result<()> {
    if v != 0.0 && v.is_finite() && !(1e-6..1e21).contains(&v.abs()) {
        write!(out, "{v:e}")
    } else {
        write!(out, "{v}")
    }
}

/// Writes one row (`mode`: the Markov mode index, for a spec with modes).
pub fn row(
    out: &mut dyn Write,
    t: f64,
    x: &[f64],
    u: &[f64],
    sent: bool,
    mode: Option<usize>,
) -> io::Result<()> {
    number(out, t)?;
    for &v in x.iter().chain(u) {
        out.write_all(b",")?;
        number(out, v)?;
    }
    out.write_all(if sent { b",1" } else { b",0" })?;
    if let Some(a) = mode {
        write!(out, ",{a}")?;
    }
    out.write_all(b"\n")
}

/// A file written through a temporary sibling and renamed into place by
/// [`AtomicFile::commit`]; dropped uncommitted, it removes the temporary.
pub struct AtomicFile {
    path: PathBuf,
    tmp: PathBuf,
    out: Option<BufWriter<File>>,
}

fn refuse_special(path: &Path) -> io::Result<()> {
    match std::fs::symlink_metadata(path) {
        Ok(m) if !m.file_type().is_file() => Err(io::Error::other(format!(
            "`{}` exists and is not a regular file",
            path.display()
        ))),
        _ => Ok(()),
    }
}

/// Whether two files have the same bytes (read in chunks).
fn same_bytes(a: &Path, b: &Path) -> io::Result<bool> {
    if std::fs::metadata(a)?.len() != std::fs::metadata(b)?.len() {
        return Ok(false);
    }
    let (mut fa, mut fb) = (File::open(a)?, File::open(b)?);
    let (mut ba, mut bb) = (vec![0u8; 1 << 16], vec![0u8; 1 << 16]);
    loop {
        let k = fa.read(&mut ba)?;
        if k == 0 {
            return Ok(true);
        }
        fb.read_exact(&mut bb[..k])?;
        if ba[..k] != bb[..k] {
            return Ok(false);
        }
    }
}

impl AtomicFile {
    /// Starts writing `path` (its folder is created). Refuses a target that
    /// exists and is not a regular file (device, FIFO, folder, symlink).
    pub fn create(path: &Path) -> io::Result<Self> {
        refuse_special(path)?;
        let dir = path
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        std::fs::create_dir_all(dir)?;
        let name = path
            .file_name()
            .map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
        let tmp = dir.join(format!(".{name}.tmp{}", std::process::id()));
        let file = OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(true)
            .open(&tmp)?;
        Ok(AtomicFile {
            path: path.to_path_buf(),
            tmp,
            out: Some(BufWriter::new(file)),
        })
    }

    /// The writer of the temporary file.
    pub fn writer(&mut self) -> &mut dyn Write {
        match &mut self.out {
            Some(w) => w,
            // ok: `out` is only taken by `commit`, which consumes self.
            None => unreachable!("AtomicFile used after commit"),
        }
    }

    /// Flushes and renames the temporary over the target (left untouched,
    /// with its timestamp, when it already has the same bytes).
    pub fn commit(mut self) -> io::Result<()> {
        if let Some(w) = self.out.take() {
            w.into_inner().map_err(|e| e.into_error())?.sync_all()?;
        }
        refuse_special(&self.path)?;
        if same_bytes(&self.path, &self.tmp).unwrap_or(false) {
            return std::fs::remove_file(&self.tmp);
        }
        std::fs::rename(&self.tmp, &self.path)
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        // After a successful rename the temporary no longer exists.
        let _ = std::fs::remove_file(&self.tmp);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn text(v: f64) -> String {
        let mut out = Vec::new();
        number(&mut out, v).expect("in memory"); // ok: unit test
        String::from_utf8(out).expect("ASCII") // ok: unit test
    }

    #[test]
    fn numbers_are_short_and_round_trip() {
        for (v, want) in [
            (0.0, "0"),
            (0.001, "0.001"),
            (-1.5, "-1.5"),
            (1e-6, "0.000001"),
            (9.99e-7, "9.99e-7"),
            (1.5e-300, "1.5e-300"),
            (1e21, "1e21"),
            (f64::NAN, "NaN"),
            (f64::NEG_INFINITY, "-inf"),
        ] {
            assert_eq!(text(v), want);
        }
        for v in [
            f64::MIN_POSITIVE,
            5e-324,
            1.2345678901234567e-7,
            f64::MAX,
            0.1 + 0.2,
        ] {
            let s = text(v);
            assert!(s.len() <= 25, "{s}");
            assert_eq!(s.parse::<f64>(), Ok(v), "{s}");
        }
    }
}
