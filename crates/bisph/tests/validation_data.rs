//! The experiment data of the validation cases: found through `BISPH_DATA` (a copy of the
//! repository's `data/` folder, nothing outside it) and checked before any simulation starts.

mod common;

use common::temp_dir;
use std::path::Path;
use std::process::Command;

/// Copies the folder `from` into `to`, recursively.
fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            copy_dir(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), target).unwrap();
        }
    }
}

/// `bisph validate --quick NAME --out OUT` with `BISPH_DATA` set to `data`.
fn validate_with_data(data: &Path, name: &str, out: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_bisph"))
        .args(["validate", "--quick", name, "--out"])
        .arg(out)
        .env("BISPH_DATA", data)
        .output()
        .expect("bisph runs")
}

#[test]
fn missing_data_is_named_before_any_simulation() {
    let dir = temp_dir("data", "missing");
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let out = dir.join("out");
    let run = validate_with_data(&empty, "spheric-test2", &out);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    let tried = empty.join("spheric-test2/kleefsman2005-p1-p4-h1-h4.dat");
    assert!(stderr.contains("spheric-test2"), "{stderr}");
    assert!(stderr.contains(&tried.display().to_string()), "{stderr}");
    assert!(stderr.contains("BISPH_DATA"), "{stderr}");
    assert!(!stderr.contains("validating"), "a case started: {stderr}");
    assert!(!out.exists(), "outputs were written");
}

#[test]
fn damaged_data_is_named_with_its_line() {
    let dir = temp_dir("data", "damaged");
    let data = dir.join("data");
    copy_dir(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data"),
        &data,
    );
    let file = data.join("spheric-test2/kleefsman2005-p1-p4-h1-h4.dat");
    let text = std::fs::read_to_string(&file).unwrap();
    std::fs::write(&file, text.replacen("0.0010289056", "0.00l0289056", 1)).unwrap();
    let run = validate_with_data(&data, "spheric-test2", &dir.join("out"));
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains(&file.display().to_string()), "{stderr}");
    assert!(stderr.contains("line 3"), "{stderr}");
}

#[test]
fn spheric_test2_validates_from_a_copy_of_the_data() {
    let dir = temp_dir("data", "copy");
    let data = dir.join("data");
    copy_dir(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data"),
        &data,
    );
    let out = dir.join("out");
    let run = validate_with_data(&data, "spheric-test2", &out);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(0), "{stderr}");
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(report.contains("front arrival at P1"), "{report}");
}
