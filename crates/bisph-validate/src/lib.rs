//! # bisph-validate
//!
//! `bisph validate`: validation cases, each comparing measured quantities with a reference
//! and a tolerance, and a report (table on stdout, `report.md` with plots).
//!
//! A validation case implements [`ValidationCase`]; [`registry`] lists them all. Cases run at
//! a quick resolution in CI (`--quick`) and at full resolution otherwise. One file per paper
//! or family of cases; what they share (loading and running a case file, reading the CSV
//! columns of a run, plots) is in [`support`].

#![deny(missing_docs)]

pub mod apollo;
pub mod check;
pub mod data;
pub mod packing;
pub mod paper1;
pub mod paper2;
pub mod paper3;
pub mod paper3_flow;
pub mod report;
pub mod rigid;
pub mod spheric2;
pub mod still_water;
pub mod support;
pub mod wave;

pub use check::{CaseReport, Check, Tolerance, ValidationCase};
pub use report::{markdown, table};

/// Every validation case bisph knows, in the order of the report.
pub fn registry() -> Vec<Box<dyn ValidationCase>> {
    let mut cases = Vec::new();
    cases.extend(paper1::cases());
    cases.extend(paper2::cases());
    cases.extend(paper3::cases());
    cases.extend(paper3_flow::cases());
    cases.extend(packing::cases());
    cases.extend(rigid::cases());
    cases.extend(spheric2::cases());
    cases.extend(apollo::cases());
    cases.extend(still_water::cases());
    cases
}
