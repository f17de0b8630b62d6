//! Statement coverage, as `harness coverage`, `summary.md` and `index.html` show it: per
//! manual and section, the statements the inventories list (`suites/inventory/`), how many a
//! case asserts, how many wait for a bus binding, how many cannot be tested here, how many are
//! open — and each manual's total. One table of rows, so the three cannot disagree.

use std::fmt::Write;

use super::markup::text;
use crate::outcome::StatementCoverage;

/// The section rows, each manual followed by its total (section `all`), in the inventories'
/// order.
fn rows(sections: &[StatementCoverage]) -> Vec<StatementCoverage> {
    let mut out: Vec<StatementCoverage> = Vec::new();
    let mut total: Option<StatementCoverage> = None;
    for s in sections {
        if total
            .as_ref()
            .is_some_and(|t| (&t.doc, &t.edition) != (&s.doc, &s.edition))
        {
            out.extend(total.take());
        }
        total
            .get_or_insert_with(|| StatementCoverage {
                doc: s.doc.clone(),
                edition: s.edition.clone(),
                section: "all".into(),
                ..StatementCoverage::default()
            })
            .add(s);
        out.push(s.clone());
    }
    out.extend(total);
    out
}

const COLUMNS: [&str; 8] = [
    "doc",
    "edition",
    "section",
    "statements",
    "asserted",
    "pending",
    "untestable",
    "open",
];

fn cells(r: &StatementCoverage) -> [String; 9] {
    [
        r.doc.clone(),
        r.edition.clone(),
        r.section.clone(),
        r.statements.to_string(),
        r.asserted.to_string(),
        r.pending.to_string(),
        r.untestable.to_string(),
        r.open().to_string(),
        format!("{:.0} %", r.percent()),
    ]
}

/// `harness coverage`: an aligned text table.
pub(crate) fn text_table(sections: &[StatementCoverage]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<8} {:<11} {:<10} {:>10} {:>8} {:>7} {:>10} {:>5} {:>9}",
        COLUMNS[0],
        COLUMNS[1],
        COLUMNS[2],
        COLUMNS[3],
        COLUMNS[4],
        COLUMNS[5],
        COLUMNS[6],
        COLUMNS[7],
        "asserted/testable"
    );
    for r in rows(sections) {
        let c = cells(&r);
        let _ = writeln!(
            s,
            "{:<8} {:<11} {:<10} {:>10} {:>8} {:>7} {:>10} {:>5} {:>9}",
            c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7], c[8]
        );
    }
    s
}

/// `## Statement coverage by manual section` for `summary.md` (nothing without inventories).
pub(super) fn markdown(s: &mut String, sections: &[StatementCoverage]) {
    if sections.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "\n## Statement coverage by manual section\n\nWhat the manuals state (`suites/inventory/`), and how much of it the cases assert; `open` is testable and not asserted yet.\n\n| {} | asserted / testable |\n|---|---|---|---:|---:|---:|---:|---:|---:|",
        COLUMNS.join(" | ")
    );
    for r in rows(sections) {
        let c = cells(&r).map(|v| v.replace('|', "\\|"));
        let line = if r.section == "all" {
            c.map(|v| format!("**{v}**")).join(" | ")
        } else {
            c.join(" | ")
        };
        let _ = writeln!(s, "| {line} |");
    }
}

/// The same table for `index.html`; its rows carry `data-doc` so the manual filter applies.
pub(super) fn html(s: &mut String, sections: &[StatementCoverage]) {
    if sections.is_empty() {
        return;
    }
    let head: String = COLUMNS.iter().map(|c| format!("<th>{c}</th>")).collect();
    let _ = writeln!(
        s,
        "<section id=\"statements\"><h2>Statement coverage by manual and section</h2>\n<p>What the manuals state (<code>suites/inventory/</code>), and how much of it the cases assert; <em>open</em> is testable and not asserted yet.</p>\n<table><thead><tr>{head}<th>asserted / testable</th></tr></thead><tbody>"
    );
    for r in rows(sections) {
        let class = if r.section == "all" {
            " class=\"total\""
        } else {
            ""
        };
        let c = cells(&r);
        let _ = write!(s, "<tr data-doc=\"{}\"{class}>", text(&r.doc));
        for (i, v) in c.iter().enumerate() {
            let num = if i >= 3 { " class=\"n\"" } else { "" };
            let _ = write!(s, "<td{num}>{}</td>", text(v));
        }
        s.push_str("</tr>\n");
    }
    s.push_str("</tbody></table></section>\n");
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::fixtures::sample_run;

    #[test]
    fn each_manual_ends_with_its_total() {
        let r = rows(&sample_run().statements);
        let last = r.last().unwrap();
        assert_eq!(
            (
                last.section.as_str(),
                last.statements,
                last.asserted,
                last.pending,
                last.open()
            ),
            ("all", 7, 5, 1, 1)
        );
        assert_eq!(format!("{:.0}", last.percent()), "83");
    }

    #[test]
    fn the_three_renderings_show_the_same_rows() {
        let sections = sample_run().statements;
        let t = text_table(&sections);
        assert!(t.contains("2.2.7"), "{t}");
        assert!(t.lines().last().unwrap().contains("83 %"), "{t}");
        let mut md = String::new();
        markdown(&mut md, &sections);
        assert!(
            md.contains("| BU 0620 | 2020-03 en | 2.2.7 | 4 | 2 | 1 | 0 | 1 | 67 % |"),
            "{md}"
        );
        assert!(
            md.contains("| **BU 0620** | **2020-03 en** | **all** | **7** |"),
            "{md}"
        );
        let mut h = String::new();
        html(&mut h, &sections);
        assert!(
            h.contains("<tr data-doc=\"BU 0620\" class=\"total\"><td>BU 0620</td>"),
            "{h}"
        );
        assert!(h.contains("<td class=\"n\">83 %</td>"), "{h}");
        let mut none = String::new();
        markdown(&mut none, &[]);
        html(&mut none, &[]);
        assert!(none.is_empty());
    }
}
