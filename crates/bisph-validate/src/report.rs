//! The report of a validation run: the table printed on stdout and `report.md`.

use crate::check::CaseReport;
use std::fmt::Write as _;

/// The table printed on stdout.
pub fn table(reports: &[CaseReport]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<22} {:<44} {:>13} {:>13} {:>12} {:>5}",
        "case", "quantity", "value", "reference", "tolerance", "pass"
    );
    for r in reports {
        for c in &r.checks {
            let _ = writeln!(
                s,
                "{:<22} {:<44} {:>13.5e} {:>13.5e} {:>12} {:>5}",
                r.name,
                c.quantity,
                c.value,
                c.reference,
                c.tolerance_text(),
                c.verdict()
            );
        }
    }
    s
}

/// `report.md`: the table, the notes and the plots of every case.
pub fn markdown(reports: &[CaseReport], quick: bool) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# bisph validation report ({})\n",
        if quick { "quick" } else { "full" }
    );
    for r in reports {
        let _ = writeln!(s, "## {} ({:.1} s)\n", r.name, r.wall_seconds);
        let _ = writeln!(
            s,
            "| quantity | value | reference | tolerance | pass | source |"
        );
        let _ = writeln!(s, "| --- | ---: | ---: | --- | --- | --- |");
        for c in &r.checks {
            let _ = writeln!(
                s,
                "| {} | {:.5e} | {:.5e} | {} | {} | {} |",
                c.quantity,
                c.value,
                c.reference,
                c.tolerance_text(),
                c.verdict(),
                match &c.known_failure_reason {
                    Some(why) => format!("{} (known failure: {why})", c.source),
                    None => c.source.clone(),
                }
            );
        }
        for n in &r.notes {
            let _ = writeln!(s, "\n{n}");
        }
        for p in &r.plots {
            let _ = writeln!(s, "\n![{}]({})", p.display(), p.display());
        }
        let _ = writeln!(s);
    }
    s
}
