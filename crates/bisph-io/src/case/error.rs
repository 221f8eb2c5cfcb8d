//! The named error of a case file: which file, which key, what was expected.

use std::fmt;

/// An error in a case file: which file, which key, what was expected.
#[derive(Debug, Clone, PartialEq)]
pub struct CaseError {
    /// The case file (or `<built-in>`).
    pub file: String,
    /// Dotted key path (empty when the whole file is at fault).
    pub key: String,
    /// What was wrong and what was expected.
    pub message: String,
}

impl fmt::Display for CaseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.key.is_empty() {
            write!(f, "{}: {}", self.file, self.message)
        } else {
            write!(f, "{}: key `{}`: {}", self.file, self.key, self.message)
        }
    }
}

impl std::error::Error for CaseError {}
