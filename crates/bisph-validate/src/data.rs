//! Experiment data that validation cases compare with (the project's `data/` folder): where
//! it is found at run time, and the error listing every path tried when it is not.

use std::path::{Path, PathBuf};

/// Environment variable naming the data folder; when set, it is the only folder searched.
pub const DATA_ENV: &str = "BISPH_DATA";

/// Folders searched for the data, in order: `$BISPH_DATA` alone when it is set; otherwise
/// `data/` next to the running executable, `data/` in the executable's parent folder, and the
/// source tree's `data/`.
pub fn data_dirs() -> Vec<PathBuf> {
    if let Some(dir) = std::env::var_os(DATA_ENV).filter(|v| !v.is_empty()) {
        return vec![PathBuf::from(dir)];
    }
    let mut dirs = Vec::new();
    if let Some(bin) = std::env::current_exe()
        .ok()
        .and_then(|exe| exe.parent().map(Path::to_path_buf))
    {
        dirs.push(bin.join("data"));
        if let Some(parent) = bin.parent() {
            dirs.push(parent.join("data"));
        }
    }
    dirs.push(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data"));
    dirs
}

/// The path of the data file `relative` (e.g. `spheric-test2/FILE`) in the first data folder
/// that holds it.
pub fn find(relative: &str) -> Result<PathBuf, String> {
    find_in(&data_dirs(), relative)
}

/// [`find`] over the folders `dirs`.
pub fn find_in(dirs: &[PathBuf], relative: &str) -> Result<PathBuf, String> {
    let tried: Vec<PathBuf> = dirs.iter().map(|d| d.join(relative)).collect();
    if let Some(found) = tried.iter().find(|p| p.is_file()) {
        return Ok(found.clone());
    }
    let list: Vec<String> = tried.iter().map(|p| p.display().to_string()).collect();
    Err(format!(
        "experiment data file `{relative}` not found; tried: {}; set {DATA_ENV} to the folder \
         holding it (the `data/` folder of the bisph repository)",
        list.join(", ")
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_folder_holding_the_file_wins() {
        let scratch = tempfile::Builder::new()
            .prefix("bisph-data-find-")
            .tempdir()
            .unwrap();
        let root = scratch.path();
        let (a, b) = (root.join("a"), root.join("b"));
        std::fs::create_dir_all(b.join("case")).unwrap();
        std::fs::write(b.join("case/x.dat"), "1").unwrap();
        let dirs = [a.clone(), b.clone()];
        assert_eq!(find_in(&dirs, "case/x.dat").unwrap(), b.join("case/x.dat"));
        let err = find_in(&dirs, "case/y.dat").unwrap_err();
        assert!(
            err.contains(&a.join("case/y.dat").display().to_string()),
            "{err}"
        );
        assert!(
            err.contains(&b.join("case/y.dat").display().to_string()),
            "{err}"
        );
        assert!(err.contains(DATA_ENV), "{err}");
    }
}
