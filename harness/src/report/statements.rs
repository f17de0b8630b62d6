//! Statement coverage, as `harness coverage`, `summary.md` and `index.html` show it: per
//! manual and section, the statements the inventories list (`suites/inventory/`), how many a
//! case asserts, how many wait for a bus binding, how many cannot be tested here, how many are
//! open — and each manual's total. One table of rows, so the three cannot disagree.

use std::fmt::Write;

use super::markup::text;
use crate::outcome::{SectionCount, StatementCoverage};

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

const COLUMNS: [&str; 9] = [
    "doc",
    "edition",
    "section",
    "statements",
    "on device",
    "model only",
    "pending",
    "untestable",
    "open",
];

/// The two shares' headings: asserted on the device, and by any case, of the testable.
const SHARES: [&str; 2] = ["on device / testable", "asserted / testable"];

/// A share in whole per cent; `—` when the section has nothing testable.
fn share(p: Option<f64>) -> String {
    p.map_or("—".into(), |p| format!("{p:.0} %"))
}

fn cells(r: &StatementCoverage) -> [String; 11] {
    [
        r.doc.clone(),
        r.edition.clone(),
        r.section.clone(),
        r.statements.to_string(),
        r.asserted.to_string(),
        r.model_only.to_string(),
        r.pending.to_string(),
        r.untestable.to_string(),
        r.open().to_string(),
        share(r.device_percent()),
        share(r.percent()),
    ]
}

/// `harness coverage`: an aligned text table.
pub(crate) fn text_table(sections: &[StatementCoverage]) -> String {
    let mut s = String::new();
    let line = |s: &mut String, c: &[&str]| {
        let _ = writeln!(
            s,
            "{:<8} {:<11} {:<10} {:>10} {:>9} {:>10} {:>7} {:>10} {:>5} {:>20} {:>19}",
            c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7], c[8], c[9], c[10]
        );
    };
    let head: Vec<&str> = COLUMNS.iter().chain(&SHARES).copied().collect();
    line(&mut s, &head);
    for r in rows(sections) {
        let c = cells(&r);
        line(&mut s, &c.each_ref().map(String::as_str));
    }
    s
}

/// A manual's table of contents in one sentence, the same for the terminal and `summary.md`.
fn sections_sentence(c: &SectionCount) -> String {
    format!(
        "sections: {} in the table of contents, {} with statements, {} with nothing testable (reasons given)",
        c.contents, c.with_statements, c.nothing
    )
}

/// `harness coverage`: one line per manual on its table of contents, so a section the
/// inventory forgot cannot hide (every section holds statements or says why it has none).
pub(crate) fn sections_text(counts: &[SectionCount]) -> String {
    let mut s = String::new();
    for c in counts {
        let _ = writeln!(s, "{:<8} {:<11} {}", c.doc, c.edition, sections_sentence(c));
    }
    s
}

/// The same lines for `summary.md`, below the statement table (nothing without inventories).
pub(super) fn sections_markdown(s: &mut String, counts: &[SectionCount]) {
    if counts.is_empty() {
        return;
    }
    let _ = writeln!(s);
    for c in counts {
        let _ = writeln!(s, "- {} {}: {}", c.doc, c.edition, sections_sentence(c));
    }
}

/// What the columns mean, for `summary.md` and `index.html`.
const LEGEND: &str = "*on device*: a case that reaches the DUT asserts it; *model only*: only reference-model checks (`compute`, never the DUT) do; *open*: testable and not asserted yet; — : nothing testable in the section.";

/// `## Statement coverage by manual section` for `summary.md` (nothing without inventories).
pub(super) fn markdown(s: &mut String, sections: &[StatementCoverage]) {
    if sections.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "\n## Statement coverage by manual section\n\nWhat the manuals state (`suites/inventory/`), and how much of it the cases assert. {LEGEND}\n\n| {} | {} |\n|---|---|---|{}",
        COLUMNS.join(" | "),
        SHARES.join(" | "),
        "---:|".repeat(COLUMNS.len() - 3 + SHARES.len())
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

/// The same table for `index.html`; its rows carry `data-doc` so the manual filter applies,
/// and the counts as data for the page's self-check.
pub(super) fn html(s: &mut String, sections: &[StatementCoverage]) {
    if sections.is_empty() {
        return;
    }
    let head: String = COLUMNS
        .iter()
        .chain(&SHARES)
        .map(|c| format!("<th>{c}</th>"))
        .collect();
    let _ = writeln!(
        s,
        "<section id=\"statements\"><h2>Statement coverage by manual and section</h2>\n<p>What the manuals state (<code>suites/inventory/</code>), and how much of it the cases assert. {}</p>\n<table><thead><tr>{head}</tr></thead><tbody>",
        markdown_legend_as_html()
    );
    for r in rows(sections) {
        // A manual's total carries its count for the page's self-check against the map.
        let class = if r.section == "all" {
            format!(" class=\"total\" data-statements=\"{}\"", r.statements)
        } else {
            String::new()
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

/// [`LEGEND`] with its Markdown emphasis and code as HTML.
fn markdown_legend_as_html() -> String {
    let mut out = String::new();
    let (mut em, mut code) = (false, false);
    for ch in text(LEGEND).chars() {
        match ch {
            '*' => {
                out.push_str(if em { "</em>" } else { "<em>" });
                em = !em;
            }
            '`' => {
                out.push_str(if code { "</code>" } else { "<code>" });
                code = !code;
            }
            c => out.push(c),
        }
    }
    out
}

/// Where a section stands, as the coverage map colours it: its statements by status.
const MAP_PARTS: [(&str, &str); 5] = [
    ("device", "asserted on the device"),
    ("model", "model only"),
    ("untestable", "untestable"),
    ("pending", "pending a bus binding"),
    ("open", "open"),
];

fn map_counts(r: &StatementCoverage) -> [usize; 5] {
    [r.asserted, r.model_only, r.untestable, r.pending, r.open()]
}

/// Pixels per statement in the coverage map.
const MAP_SCALE: usize = 6;

/// The coverage map for `index.html`: a row per manual, a tile per section as wide as its
/// statements, coloured in proportion by where they stand, so a gap (open, model only) shows
/// at a glance; each tile's title says the numbers, and the manual's total follows its name.
/// Plain HTML and CSS.
pub(super) fn html_map(s: &mut String, sections: &[StatementCoverage]) {
    if sections.is_empty() {
        return;
    }
    s.push_str("<section id=\"coverage-map\"><h2>Coverage map: manuals × sections</h2>\n<p class=\"legend\">");
    for (class, label) in MAP_PARTS {
        let _ = write!(s, "<span><i class=\"st-{class}\"></i> {label}</span> ");
    }
    s.push_str("</p>\n");
    let parts = |r: &StatementCoverage| -> Vec<String> {
        MAP_PARTS
            .iter()
            .zip(map_counts(r))
            .filter(|(_, n)| *n > 0)
            .map(|((_, label), n)| format!("{n} {label}"))
            .collect()
    };
    // Each manual's sections come before its total (`all`), which closes its row.
    let mut in_row = false;
    for r in rows(sections) {
        if r.section == "all" {
            let _ = writeln!(
                s,
                "</div><p class=\"map-total\">{} statements: {}</p></div>",
                r.statements,
                text(&parts(&r).join(", "))
            );
            in_row = false;
            continue;
        }
        if !in_row {
            let _ = write!(
                s,
                "<div class=\"map-row\" data-doc=\"{0}\"><h3>{0} <small>{1}</small></h3><div class=\"map-tiles\">",
                text(&r.doc),
                text(&r.edition)
            );
            in_row = true;
        }
        let _ = write!(
            s,
            "<span class=\"tile\" style=\"width:{}px\" data-section=\"{}\" title=\"{}\">",
            MAP_SCALE * r.statements.max(1),
            text(&r.section),
            text(&format!(
                "§{}: {} statements: {}",
                r.section,
                r.statements,
                parts(&r).join(", ")
            ))
        );
        for ((class, _), n) in MAP_PARTS.iter().zip(map_counts(&r)) {
            if n > 0 {
                let _ = write!(
                    s,
                    "<i class=\"st-{class}\" style=\"flex-grow:{n}\" data-n=\"{n}\"></i>"
                );
            }
        }
        s.push_str("</span>");
    }
    s.push_str("</section>\n");
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
                last.model_only,
                last.pending,
                last.untestable,
                last.open()
            ),
            ("all", 8, 4, 1, 1, 1, 1)
        );
        assert_eq!(share(last.device_percent()), "67 %");
        assert_eq!(share(last.percent()), "83 %");
    }

    #[test]
    fn each_manual_counts_its_table_of_contents() {
        let counts = sample_run().sections;
        let line = "BU 0620  2020-03 en  sections: 5 in the table of contents, 3 with statements, 2 with nothing testable (reasons given)\n";
        assert_eq!(sections_text(&counts), line);
        let mut md = String::new();
        sections_markdown(&mut md, &counts);
        assert_eq!(
            md,
            "\n- BU 0620 2020-03 en: sections: 5 in the table of contents, 3 with statements, 2 with nothing testable (reasons given)\n"
        );
        let mut none = String::new();
        sections_markdown(&mut none, &[]);
        assert!(none.is_empty());
    }

    #[test]
    fn the_three_renderings_show_the_same_rows() {
        let sections = sample_run().statements;
        let t = text_table(&sections);
        assert!(t.contains("2.2.7"), "{t}");
        assert!(
            t.lines().next().unwrap().contains("on device / testable"),
            "{t}"
        );
        assert!(
            t.lines()
                .last()
                .unwrap()
                .ends_with("67 %                83 %"),
            "{t}"
        );
        // Nothing testable in §2.6.1: a dash, not 100 %.
        let untestable = t.lines().find(|l| l.contains("2.6.1")).unwrap();
        assert!(untestable.ends_with("—                   —"), "{t}");
        let mut md = String::new();
        markdown(&mut md, &sections);
        assert!(
            md.contains("| doc | edition | section | statements | on device | model only | pending | untestable | open | on device / testable | asserted / testable |\n|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n"),
            "{md}"
        );
        assert!(
            md.contains("| BU 0620 | 2020-03 en | 2.2.7 | 4 | 1 | 1 | 1 | 0 | 1 | 33 % | 67 % |"),
            "{md}"
        );
        assert!(
            md.contains("| BU 0620 | 2020-03 en | 2.6.1 | 1 | 0 | 0 | 0 | 1 | 0 | — | — |"),
            "{md}"
        );
        assert!(
            md.contains("| **BU 0620** | **2020-03 en** | **all** | **8** | **4** | **1** |"),
            "{md}"
        );
        let mut h = String::new();
        html(&mut h, &sections);
        assert!(
            h.contains(
                "<tr data-doc=\"BU 0620\" class=\"total\" data-statements=\"8\"><td>BU 0620</td>"
            ),
            "{h}"
        );
        assert!(
            h.contains("<td class=\"n\">67 %</td><td class=\"n\">83 %</td></tr>"),
            "{h}"
        );
        assert!(
            h.contains("<em>model only</em>: only reference-model checks (<code>compute</code>"),
            "{h}"
        );
        let mut none = String::new();
        markdown(&mut none, &[]);
        html(&mut none, &[]);
        html_map(&mut none, &[]);
        assert!(none.is_empty());
    }

    #[test]
    fn the_map_colours_each_section_by_where_its_statements_stand() {
        let mut h = String::new();
        html_map(&mut h, &sample_run().statements);
        assert_eq!(h.matches("<div class=\"map-row\"").count(), 1, "{h}");
        // §2.2.7: 4 statements, 24 px; one on the device, one model only, one pending, one open.
        assert!(
            h.contains("<span class=\"tile\" style=\"width:24px\" data-section=\"2.2.7\" title=\"§2.2.7: 4 statements: 1 asserted on the device, 1 model only, 1 pending a bus binding, 1 open\"><i class=\"st-device\" style=\"flex-grow:1\" data-n=\"1\"></i><i class=\"st-model\" style=\"flex-grow:1\" data-n=\"1\"></i><i class=\"st-pending\" style=\"flex-grow:1\" data-n=\"1\"></i><i class=\"st-open\" style=\"flex-grow:1\" data-n=\"1\"></i></span>"),
            "{h}"
        );
        assert!(h.contains("data-section=\"2.6.1\" title=\"§2.6.1: 1 statements: 1 untestable\"><i class=\"st-untestable\""), "{h}");
        assert!(
            h.contains("</div><p class=\"map-total\">8 statements: 4 asserted on the device, 1 model only, 1 untestable, 1 pending a bus binding, 1 open</p></div>"),
            "{h}"
        );
        // Tags balance: every row and its tiles close.
        assert_eq!(
            h.matches("<div").count(),
            h.matches("</div>").count(),
            "{h}"
        );
        assert_eq!(
            h.matches("<span").count(),
            h.matches("</span>").count(),
            "{h}"
        );
    }
}
