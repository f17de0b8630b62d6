//! `harness coverage`'s errata table: per manual and edition, how many errata the suites
//! record and which check of the errata pass found them, so a reviewer sees at a glance that a
//! manual was held against its standard and the other manuals, not only read.

use std::collections::BTreeMap;
use std::fmt::Write;

use crate::outcome::Erratum;

/// An aligned text table: doc, edition, errata, one column per check, ambiguous.
pub(crate) fn text_table(errata: &[Erratum]) -> String {
    let mut per_manual: BTreeMap<(&str, &str), ([usize; 4], usize)> = BTreeMap::new();
    for e in errata {
        let (counts, ambiguous) = per_manual.entry((&e.doc, &e.edition)).or_default();
        // The columns follow the checks' declared order.
        counts[e.check as usize] += 1;
        *ambiguous += usize::from(e.ambiguous);
    }
    let doc_width = per_manual
        .keys()
        .map(|(d, _)| d.len())
        .max()
        .unwrap_or(0)
        .max(3);
    let edition_width = per_manual
        .keys()
        .map(|(_, e)| e.len())
        .max()
        .unwrap_or(0)
        .max(7);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<doc_width$} {:<edition_width$} {:>6} {:>8} {:>8} {:>12} {:>13} {:>9}",
        "doc",
        "edition",
        "errata",
        "own-text",
        "standard",
        "other-manual",
        "range-default",
        "ambiguous"
    );
    for ((doc, edition), (c, ambiguous)) in per_manual {
        let _ = writeln!(
            s,
            "{doc:<doc_width$} {edition:<edition_width$} {:>6} {:>8} {:>8} {:>12} {:>13} {ambiguous:>9}",
            c.iter().sum::<usize>(),
            c[0],
            c[1],
            c[2],
            c[3],
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::outcome::ErratumCheck;

    fn erratum(doc: &str, check: ErratumCheck, ambiguous: bool) -> Erratum {
        Erratum {
            doc: doc.into(),
            edition: "e".into(),
            section: "1".into(),
            page: None,
            case: "c".into(),
            printed: "p".into(),
            correct: "q".into(),
            why: "w".into(),
            ambiguous,
            check,
            standard: None,
        }
    }

    #[test]
    fn each_manual_counts_its_errata_by_check() {
        let t = text_table(&[
            erratum("BU 2200", ErratumCheck::Standard, false),
            erratum("BU 2200", ErratumCheck::Standard, true),
            erratum("BU 2200", ErratumCheck::OwnText, false),
            erratum("BU 0590", ErratumCheck::RangeDefault, false),
        ]);
        let lines: Vec<Vec<&str>> = t.lines().map(|l| l.split_whitespace().collect()).collect();
        assert_eq!(lines[1], ["BU", "0590", "e", "1", "0", "0", "0", "1", "0"]);
        assert_eq!(lines[2], ["BU", "2200", "e", "3", "1", "2", "0", "0", "1"]);
    }
}
