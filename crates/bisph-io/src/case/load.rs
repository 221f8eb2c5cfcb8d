//! Reading a case file: the TOML text, `--set a.b=value` overrides applied before parsing,
//! strict parsing (unknown keys, wrong types and missing values are errors that name the file,
//! the key and what was expected), then the checks.

use crate::case::check::check_case;
use crate::case::error::CaseError;
use crate::case::schema::{Case, LoadedCase};
use std::path::{Path, PathBuf};

/// The built-in default case: the 2-D dam break (`cases/dam-break-2d.toml`).
pub const DEFAULT_CASE: &str = include_str!("../../../../cases/dam-break-2d.toml");

/// Reads a case file (or the built-in default with `None`) and applies `key=value` overrides.
pub fn load_case(path: Option<&Path>, overrides: &[String]) -> Result<LoadedCase, CaseError> {
    let (source, text) = match path {
        Some(p) => {
            let source = p.display().to_string();
            let text = std::fs::read_to_string(p).map_err(|e| CaseError {
                file: source.clone(),
                key: String::new(),
                message: format!("cannot read the case file: {e}"),
            })?;
            (source, text)
        }
        None => (
            "<built-in dam-break-2d>".to_string(),
            DEFAULT_CASE.to_string(),
        ),
    };
    parse_case(&source, &text, overrides)
}

/// Parses case text, applies overrides, checks it.
pub fn parse_case(source: &str, text: &str, overrides: &[String]) -> Result<LoadedCase, CaseError> {
    let err = |key: &str, message: String| CaseError {
        file: source.to_string(),
        key: key.to_string(),
        message,
    };
    let mut doc: toml::Table = text.parse().map_err(|e: toml::de::Error| {
        let at = e
            .span()
            .map_or(String::new(), |span| line_column(text, span.start));
        err(
            "",
            format!("not valid TOML{at}: {}", e.message().trim_end()),
        )
    })?;
    for item in overrides {
        let Some((key, value)) = item.split_once('=') else {
            return Err(err(
                item,
                "an override must read key=value (e.g. resolution.dx=0.01)".into(),
            ));
        };
        let value = parse_override_value(value.trim());
        set_dotted(&mut doc, key.trim(), value).map_err(|m| err(key.trim(), m))?;
    }
    let text =
        toml::to_string(&doc).map_err(|e| err("", format!("cannot re-serialise the case: {e}")))?;
    let case: Case = toml::from_str(&text).map_err(|e| {
        let span_key = key_of_error(&text, &e);
        err(&span_key, e.message().to_string())
    })?;
    let loaded = LoadedCase {
        case,
        source: source.to_string(),
        text,
    };
    check_case(&loaded)?;
    Ok(loaded)
}

/// An override value: TOML if it parses as one (number, bool, array), else a string.
fn parse_override_value(raw: &str) -> toml::Value {
    let wrapped = format!("v = {raw}");
    match wrapped.parse::<toml::Table>() {
        Ok(mut t) => t
            .remove("v")
            .unwrap_or(toml::Value::String(raw.to_string())),
        Err(_) => toml::Value::String(raw.to_string()),
    }
}

/// Sets `a.b.c` (array entries by index, `fluid_block.0.min`) in a TOML table.
fn set_dotted(doc: &mut toml::Table, key: &str, value: toml::Value) -> Result<(), String> {
    let parts: Vec<&str> = key.split('.').collect();
    if parts.iter().any(|p| p.is_empty()) {
        return Err("an empty segment in the dotted key".into());
    }
    let mut node = doc
        .entry(parts[0].to_string())
        .or_insert_with(|| toml::Value::Table(toml::Table::new()));
    if parts.len() == 1 {
        *node = value;
        return Ok(());
    }
    for (depth, part) in parts.iter().enumerate().skip(1) {
        let last = depth == parts.len() - 1;
        node = match node {
            toml::Value::Table(t) => {
                if last {
                    t.insert(part.to_string(), value);
                    return Ok(());
                }
                t.entry(part.to_string())
                    .or_insert_with(|| toml::Value::Table(toml::Table::new()))
            }
            toml::Value::Array(a) => {
                let index: usize = part
                    .parse()
                    .map_err(|_| format!("`{part}` should be an index into a list"))?;
                let len = a.len();
                let slot = a
                    .get_mut(index)
                    .ok_or_else(|| format!("index {index} is past the list's {len} entries"))?;
                if last {
                    *slot = value;
                    return Ok(());
                }
                slot
            }
            _ => return Err(format!("`{}` is not a table", parts[..depth].join("."))),
        };
    }
    Ok(())
}

/// The dotted key at the error's span, found from the TOML text (best effort).
fn key_of_error(text: &str, e: &toml::de::Error) -> String {
    let Some(span) = e.span() else {
        return String::new();
    };
    let before = &text[..span.start.min(text.len())];
    let mut table = String::new();
    let mut index: std::collections::HashMap<String, usize> = Default::default();
    for line in before.lines() {
        let l = line.trim();
        if let Some(name) = l.strip_prefix("[[").and_then(|s| s.strip_suffix("]]")) {
            let path = indexed_path(name, &index);
            let n = index
                .entry(path.clone())
                .and_modify(|n| *n += 1)
                .or_insert(0);
            table = format!("{path}[{n}]");
        } else if let Some(name) = l.strip_prefix('[').and_then(|s| s.strip_suffix(']')) {
            table = indexed_path(name, &index);
        }
    }
    let line_start = before.rfind('\n').map_or(0, |k| k + 1);
    let line = text[line_start..].lines().next().unwrap_or("");
    // An error at a table header (an unknown table) is the header's own key.
    let header = line.trim();
    if let Some(name) = header.strip_prefix("[[").and_then(|s| s.strip_suffix("]]")) {
        let path = indexed_path(name, &index);
        let n = index.get(&path).map_or(0, |n| n + 1);
        return format!("{path}[{n}]");
    }
    if let Some(name) = header.strip_prefix('[').and_then(|s| s.strip_suffix(']')) {
        return indexed_path(name, &index);
    }
    let key = line
        .split('=')
        .next()
        .unwrap_or("")
        .trim()
        .trim_matches('"');
    let key = if key.starts_with('[') { "" } else { key };
    match (table.is_empty(), key.is_empty()) {
        (true, _) => key.to_string(),
        (false, true) => table,
        (false, false) => format!("{table}.{key}"),
    }
}

/// The dotted table name `name` with the current entry of every enclosing array of tables
/// (`fluid_block.hole` inside the second `[[fluid_block]]` is `fluid_block[1].hole`), given
/// the last index of each array seen so far.
fn indexed_path(name: &str, index: &std::collections::HashMap<String, usize>) -> String {
    let parts: Vec<&str> = name.split('.').collect();
    let mut path = String::new();
    for (k, part) in parts.iter().enumerate() {
        if k > 0 {
            path.push('.');
        }
        path.push_str(part.trim());
        if k + 1 < parts.len() {
            if let Some(n) = index.get(&path) {
                path = format!("{path}[{n}]");
            }
        }
    }
    path
}

/// ` at line L, column C` (1-based, columns in characters) of the byte offset `at` in `text`.
fn line_column(text: &str, at: usize) -> String {
    let before = &text[..at.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before[before.rfind('\n').map_or(0, |k| k + 1)..]
        .chars()
        .count()
        + 1;
    format!(" at line {line}, column {column}")
}

/// Where a run writes by default: `out/<case name>`.
pub fn default_out_dir(case: &Case) -> PathBuf {
    PathBuf::from("out").join(&case.name)
}

#[cfg(test)]
mod tests {
    use super::*;

    const CASE: &str = "name = \"t\"\ndim = 2\n[fluid]\ndensity = 1000.0\nsound_speed = 20.0\n\
        [resolution]\ndx = 0.05\n[time]\nend = 0.01\n[[fluid_block]]\nshape = \"box\"\n\
        min = [0.0, 0.0]\nmax = [0.5, 0.5]\n[[wall]]\nshape = \"box\"\nmin = [0.0, 0.0]\n\
        max = [1.0, 1.0]\n";

    #[test]
    fn syntax_errors_give_line_and_column() {
        let text = CASE.replace("dx = 0.05", "dx = = 0.05");
        let e = parse_case("c.toml", &text, &[]).unwrap_err();
        assert!(
            e.message.contains("not valid TOML at line 7, column 6"),
            "{e}"
        );
    }

    #[test]
    fn unknown_names_give_the_key_the_value_and_the_choices() {
        let hole = "[[fluid_block.hole]]\nshape = \"box\"\nmin = [0.1, 0.1]\nmax = [0.2, 0.2]\n";
        let second = "[[fluid_block]]\nshape = \"box\"\nmin = [0.5, 0.5]\nmax = [0.9, 0.9]\n";
        let text = CASE.replace("[[wall]]", &format!("{hole}{second}{hole}[[wall]]"));
        assert!(parse_case("c.toml", &text, &[]).is_ok());
        let text = CASE.replace(
            "[[wall]]",
            &format!("{hole}{second}{}[[wall]]", hole.replace("box", "ellipse")),
        );
        for (text, key, value) in [
            (text, "fluid_block[1].hole[0].shape", "ellipse"),
            (
                CASE.replacen("\"box\"", "\"cricle\"", 1),
                "fluid_block[0].shape",
                "cricle",
            ),
            (
                CASE.replacen(
                    "\"box\"\nmin = [0.0, 0.0]\nmax = [1.0",
                    "\"mesj\"\nmin = [0.0, 0.0]\nmax = [1.0",
                    1,
                ),
                "wall[0].shape",
                "mesj",
            ),
            (
                CASE.replace("max = [0.5, 0.5]", "max = [0.5, 0.5]\nfill = \"bipy\""),
                "fluid_block[0].fill",
                "bipy",
            ),
            (
                format!("{CASE}[[probe]]\nname = \"p\"\nkind = \"speed\"\nposition = [0.5, 0.5]\n"),
                "probe[0].kind",
                "speed",
            ),
        ] {
            let e = parse_case("c.toml", &text, &[]).unwrap_err();
            assert_eq!(e.key, key, "{e}");
            assert!(e.message.contains(&format!("`{value}`")), "{e}");
            assert!(e.message.contains("expected one of"), "{e}");
            assert!(e.to_string().starts_with("c.toml: "), "{e}");
        }
    }

    #[test]
    fn unknown_tables_are_reported_under_their_own_key() {
        for (table, key) in [
            ("[tme]\nend = 1.0\n", "tme"),
            ("[outptu]\nx = 1\n", "outptu"),
        ] {
            let text = CASE.replace("[time]", &format!("{table}[time]"));
            let e = parse_case("c.toml", &text, &[]).unwrap_err();
            assert_eq!(e.key, key, "{e}");
            let text = format!("{CASE}{table}");
            let e = parse_case("c.toml", &text, &[]).unwrap_err();
            assert_eq!(e.key, key, "{e}");
        }
    }
}
