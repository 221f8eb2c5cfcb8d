//! Writing files: errors that name the file, and atomic writes.

use std::fs::File;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// An I/O failure, with the file it concerns.
#[derive(Debug)]
pub struct OutputError {
    /// The file.
    pub path: PathBuf,
    /// What went wrong.
    pub source: io::Error,
}

impl std::fmt::Display for OutputError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "cannot write {}: {}", self.path.display(), self.source)
    }
}

impl std::error::Error for OutputError {}

/// Attaches the path to an I/O result.
pub fn at<T>(path: &Path, r: io::Result<T>) -> Result<T, OutputError> {
    r.map_err(|source| OutputError {
        path: path.to_path_buf(),
        source,
    })
}

/// Removes the temporary files that [`write_atomic`] and the VTK writer leave in `dir` (and its
/// `vtk/` folder) when a run is killed mid-write (`checkpoint.bin.tmp` after `kill -9`):
/// files named `NAME.tmp` where `NAME` has an extension bisph writes.
pub fn remove_stale_temporaries(dir: &Path) {
    const WRITTEN: [&str; 6] = ["bin", "json", "toml", "vtu", "pvd", "csv"];
    for folder in [dir.to_path_buf(), dir.join("vtk")] {
        let Ok(entries) = std::fs::read_dir(&folder) else {
            continue;
        };
        for entry in entries.flatten() {
            let name = entry.file_name();
            let Some(stem) = name.to_str().and_then(|n| n.strip_suffix(".tmp")) else {
                continue;
            };
            let ours = Path::new(stem)
                .extension()
                .is_some_and(|e| WRITTEN.iter().any(|w| e == *w));
            if ours && entry.file_type().is_ok_and(|t| t.is_file()) {
                let _ = std::fs::remove_file(entry.path());
            }
        }
    }
}

/// Writes `bytes` to `path` through a temporary file (synced to disk) and a rename, so a crash
/// leaves the old file or the new one, never a half-written one. On failure the temporary file
/// is removed and the old file kept.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".tmp");
    let tmp = path.with_file_name(name);
    let written = (|| {
        let mut f = File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()
    })();
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(OutputError {
            path: path.to_path_buf(),
            source: e,
        });
    }
    at(path, std::fs::rename(&tmp, path))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stale_temporaries_are_removed_and_other_files_kept() {
        let scratch = tempfile::Builder::new()
            .prefix("bisph-stale-tmp-")
            .tempdir()
            .unwrap();
        let dir = scratch.path();
        std::fs::create_dir_all(dir.join("vtk")).unwrap();
        for name in [
            "checkpoint.bin.tmp",
            "vtk/fluid_000001.vtu.tmp",
            "notes.tmp",
            "energy.csv",
        ] {
            std::fs::write(dir.join(name), "x").unwrap();
        }
        remove_stale_temporaries(dir);
        assert!(!dir.join("checkpoint.bin.tmp").exists());
        assert!(!dir.join("vtk/fluid_000001.vtu.tmp").exists());
        assert!(dir.join("notes.tmp").exists() && dir.join("energy.csv").exists());
    }
}
