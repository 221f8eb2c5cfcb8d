//! Helpers shared by the command-line test files.
// Each test file uses a subset of these.
#![allow(dead_code)]

use std::ops::Deref;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs the `bisph` binary under test with `args`.
pub fn bisph(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_bisph"))
        .args(args)
        .output()
        .expect("bisph runs")
}

/// The repository's `cases/` folder.
pub fn cases_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../cases")
}

/// A test's folder under the system's temporary folder, removed with its content when
/// dropped; used as the [`Path`] it holds.
pub struct Scratch(tempfile::TempDir);

impl Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        self.0.path()
    }
}

/// A fresh, empty folder `bisph-<tag>-<name>-<random>` under the system's temporary folder.
pub fn temp_dir(tag: &str, name: &str) -> Scratch {
    let prefix = format!("bisph-{tag}-{name}-");
    Scratch(tempfile::Builder::new().prefix(&prefix).tempdir().unwrap())
}
