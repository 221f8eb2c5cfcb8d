//! Helpers shared by the command-line test files.
// Each test file uses a subset of these.
#![allow(dead_code)]

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

/// A fresh, empty folder `bisph-<tag>-<pid>-<name>` under the system's temporary folder.
pub fn temp_dir(tag: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bisph-{tag}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
