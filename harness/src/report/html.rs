//! `index.html`: the run for a reader, one self-contained file (inline CSS and a little vanilla
//! JavaScript, nothing loaded from anywhere, so it opens from a `file://` URL or an archive).
//!
//! From the top: the overall verdict (by the exit code's rule), whether motion was allowed,
//! load errors, filters (verdict, manual), every case that did not pass — observed against
//! required, the manual clause, its transcript in a `<details>` —; then the tables: verdict
//! totals per profile with a bar each (device cases, then the model group), the not-applicable
//! cases by reason, the coverage map (manuals × sections, coloured by where their statements
//! stand), coverage by manual and section, statement coverage, the errata, and the run's
//! record. Passing and not applicable cases are counts per section only: the default run has
//! some 14,000 of them, and a row each would make the file slow to open for no reader's
//! benefit. The pictures are HTML and CSS, no image and no library.
//!
//! The filters also read the URL fragment (`#verdict=fail&manual=BU%200620`), so a link can
//! carry a filtered view. On load the script checks that the numbers it shows agree with each
//! other (profile rows sum to the totals, listed cases match the fail/error/inconclusive
//! counts, the coverage sums to the totals) and writes the outcome into `#selfcheck`, which
//! `tests/report_html.rs` reads back from a headless browser.

use std::fmt::Write;

use super::markup::text;
use super::record::{self, group_title};
use super::summary::{by_section, model_cell, not_passed, Counts};
use super::transcript;
use crate::outcome::{CaseKind, CaseResult, RunResult, Verdict};

const CSS: &str = include_str!("html.css");
const SCRIPT: &str = include_str!("html.js");

/// `<td>` cells of a count row, each tagged with its verdict.
fn count_cells(s: &mut String, n: &Counts, id_prefix: Option<&str>) {
    for v in Verdict::ALL {
        let id = id_prefix.map_or(String::new(), |p| format!(" id=\"{p}-{}\"", v.name()));
        // `nz` marks a count above zero, which the style colours.
        let nz = if n.get(v) > 0 { " nz" } else { "" };
        let _ = write!(
            s,
            "<td class=\"n v-{0}{nz}\" data-verdict=\"{0}\"{id}>{1}</td>",
            v.name(),
            n.get(v)
        );
    }
}

fn header_cells() -> String {
    Verdict::ALL
        .iter()
        .map(|v| format!("<th>{}</th>", v.name().replace('_', " ")))
        .collect()
}

fn record_table(s: &mut String, run: &RunResult) {
    s.push_str("<table id=\"record\">\n");
    for (label, value) in record::lines(run) {
        let _ = writeln!(
            s,
            "<tr><th>{}</th><td>{}</td></tr>",
            text(&label),
            text(&value)
        );
    }
    s.push_str("</table>\n");
}

fn load_errors(s: &mut String, run: &RunResult) {
    if run.load_errors.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "<section id=\"load-errors\"><h2>⚠ {} suite file(s) did not load: their cases did not run</h2><ul>",
        run.load_errors.len()
    );
    for e in &run.load_errors {
        let _ = writeln!(s, "<li><code>{}</code></li>", text(e));
    }
    s.push_str("</ul></section>\n");
}

fn totals(s: &mut String, run: &RunResult, kind: CaseKind) {
    let _ = writeln!(
        s,
        "<h3>{}</h3>\n<table id=\"totals-{}\" class=\"totals\"><thead><tr><th>profile</th>{}<th>ran: pass, fail, inconclusive, error</th></tr></thead><tbody>",
        text(group_title(kind)),
        kind.name(),
        header_cells()
    );
    for (p, n) in Counts::per_profile(run, kind) {
        if kind == CaseKind::Model && n.total() == 0 {
            continue;
        }
        let _ = write!(
            s,
            "<tr class=\"profile\" data-profile=\"{0}\"><th>{0}</th>",
            text(p)
        );
        count_cells(s, &n, None);
        let _ = writeln!(s, "<td>{}</td></tr>", bar(&n));
    }
    s.push_str("<tr class=\"all\"><th>all</th>");
    let all = Counts::of_kind(run, kind, None);
    count_cells(s, &all, Some(&format!("total-{}", kind.name())));
    let _ = writeln!(s, "<td>{}</td></tr></tbody></table>", bar(&all));
}

fn filters(s: &mut String, run: &RunResult) {
    let mut docs: Vec<&str> = run.cases.iter().map(|c| c.manual.doc.as_str()).collect();
    docs.sort_unstable();
    docs.dedup();
    s.push_str("<form id=\"filters\" onsubmit=\"return false\"><label>verdict <select id=\"f-verdict\"><option value=\"\">all</option><option value=\"not_passed\">fail, error, inconclusive</option>");
    for v in Verdict::ALL {
        let _ = write!(
            s,
            "<option value=\"{}\">{}</option>",
            v.name(),
            v.name().replace('_', " ")
        );
    }
    s.push_str(
        "</select></label> <label>manual <select id=\"f-manual\"><option value=\"\">all</option>",
    );
    for d in docs {
        let _ = write!(s, "<option value=\"{0}\">{0}</option>", text(d));
    }
    s.push_str("</select></label> <span id=\"shown\"></span></form>\n");
}

fn case_item(s: &mut String, c: &CaseResult) {
    let m = &c.manual;
    let _ = writeln!(
        s,
        "<article class=\"case v-{v}\" data-verdict=\"{v}\" data-doc=\"{doc}\" data-profile=\"{p}\" data-kind=\"{k}\">\n<h3><span class=\"badge v-{v}\">{v}</span> [{p}{model}] <code>{id}</code></h3>\n<dl>\n<dt>manual</dt><dd>{doc} ({ed}) {place}</dd>\n<dt>required</dt><dd>{title}</dd>\n<dt>observed</dt><dd>{msg}</dd>",
        v = c.verdict.name(),
        doc = text(&m.doc),
        p = text(&c.profile),
        k = c.kind.name(),
        model = if c.kind == CaseKind::Model { ", model" } else { "" },
        id = text(&c.id),
        ed = text(&m.edition),
        place = text(&m.place()),
        title = text(&record::requirement(c)),
        msg = text(&c.message),
    );
    if let Some(st) = c.deciding_step() {
        let _ = writeln!(s, "<dt>step</dt><dd><code>{}</code></dd>", text(&st.step));
        if !st.observed.is_null() {
            let _ = writeln!(
                s,
                "<dt>step observed</dt><dd><code>{}</code></dd>",
                text(&st.observed.to_string())
            );
        }
        if let Some(r) = &st.refusal {
            let _ = writeln!(
                s,
                "<dt>refusal</dt><dd>{} (code {:#x})</dd>",
                text(&r.to_string()),
                r.code
            );
        }
        if !st.message.is_empty() && st.message != c.message {
            let _ = writeln!(s, "<dt>step message</dt><dd>{}</dd>", text(&st.message));
        }
    }
    let _ = writeln!(
        s,
        "</dl>\n<details><summary>transcript</summary><pre>{}</pre></details>\n</article>",
        text(&transcript::render(c))
    );
}

fn cases(s: &mut String, run: &RunResult) {
    let _ = writeln!(s, "<section id=\"cases\"><h2>Cases that did not pass</h2>");
    let mut any = false;
    for c in not_passed(run) {
        case_item(s, c);
        any = true;
    }
    if !any {
        s.push_str("<p>None: every case passed or did not apply.</p>\n");
    }
    s.push_str("<p id=\"listed-note\">Passing and not applicable cases are counted per section below; their ids are in <code>run.json</code>.</p></section>\n");
}

fn coverage(s: &mut String, run: &RunResult) {
    let _ = writeln!(
        s,
        "<section id=\"coverage\"><h2>Coverage by manual and section</h2>\n<p>Device cases per verdict, all profiles; <em>model</em>: reference-model checks passed / run.</p>\n<table><thead><tr><th>doc</th><th>edition</th><th>section</th><th>cases</th>{}<th>model</th></tr></thead><tbody>",
        header_cells()
    );
    for ((doc, edition, _, section), cases) in by_section(run) {
        let (n, m, all) = (cases.device, cases.model, cases.all);
        // The data attributes count every case of the section, so the filter and the
        // self-check see model cases too.
        let data: String = Verdict::ALL
            .iter()
            .map(|v| format!(" data-{}=\"{}\"", v.name(), all.get(*v)))
            .collect();
        let _ = write!(
            s,
            "<tr data-doc=\"{}\"{data}><td>{}</td><td>{}</td><td>{}</td><td class=\"n\">{}</td>",
            text(doc),
            text(doc),
            text(edition),
            text(section),
            n.total()
        );
        count_cells(s, &n, None);
        let _ = writeln!(s, "<td class=\"n\">{}</td></tr>", model_cell(&m));
    }
    s.push_str("</tbody></table></section>\n");
}

fn errata(s: &mut String, run: &RunResult) {
    s.push_str(
        "<section id=\"errata\"><h2>Errata: what the manuals print, and what the cases test</h2>\n",
    );
    if run.errata.is_empty() {
        s.push_str("<p>None recorded.</p></section>\n");
        return;
    }
    s.push_str("<table><thead><tr><th>doc</th><th>edition</th><th>section</th><th>page</th><th>printed</th><th>correct</th><th>why</th><th>found by</th><th>case</th></tr></thead><tbody>\n");
    for e in &run.errata {
        let _ = writeln!(
            s,
            "<tr data-doc=\"{0}\"><td>{0}</td><td>{1}</td><td>{2}</td><td>{3}</td><td><code>{4}</code></td><td><code>{5}</code></td><td>{6}</td><td>{7}</td><td><code>{8}</code></td></tr>",
            text(&e.doc),
            text(&e.edition),
            text(&e.section),
            e.page.map_or(String::new(), |p| p.to_string()),
            text(&e.printed),
            text(&e.correct),
            text(&e.reason()),
            text(&e.found_by()),
            text(&e.case),
        );
    }
    s.push_str("</tbody></table></section>\n");
}

/// A verdict bar: the case-runs that ran (not applicable ones are not in it), a segment per
/// verdict as wide as its share; a fail, error or inconclusive segment is never too thin to see.
fn bar(n: &Counts) -> String {
    let ran: Vec<(Verdict, usize)> = Verdict::ALL
        .iter()
        .filter(|v| **v != Verdict::NotApplicable)
        .map(|v| (*v, n.get(*v)))
        .collect();
    let title: Vec<String> = ran
        .iter()
        .map(|(v, k)| format!("{k} {}", v.name()))
        .collect();
    let mut s = format!(
        "<span class=\"vbar\" title=\"{}; {} not applicable\">",
        title.join(", "),
        n.get(Verdict::NotApplicable)
    );
    for (v, k) in ran.into_iter().filter(|(_, k)| *k > 0) {
        let _ = write!(
            s,
            "<i class=\"v-{}\" style=\"flex-grow:{k}\"></i>",
            v.name()
        );
    }
    s.push_str("</span>");
    s
}

/// The whole page.
pub(super) fn render(run: &RunResult) -> String {
    let motion = if run.meta.motion_allowed {
        "motion-yes"
    } else {
        "motion-no"
    };
    let mut s = format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>Harness run: {}</title>\n<style>{CSS}</style></head>\n<body>\n",
        text(&run.dut),
    );
    super::signoff::html_banner(&mut s, run);
    let _ = writeln!(
        s,
        "<p id=\"motion\" class=\"{motion}\">{}</p>\n<h1>Harness run report: {}</h1>\n<p><output id=\"selfcheck\" data-ok=\"pending\">self-check did not run (JavaScript off?)</output> · <a href=\"#record\">the run's record</a></p>",
        text(record::motion_line(run)),
        text(&run.dut),
    );
    load_errors(&mut s, run);
    filters(&mut s, run);
    cases(&mut s, run);
    s.push_str("<section id=\"totals\"><h2>Verdicts per profile</h2>\n");
    totals(&mut s, run, CaseKind::Device);
    if run.cases.iter().any(|c| c.kind == CaseKind::Model) {
        s.push_str(
            "<p>Model cases never reach the DUT: their passes are no passes of the device.</p>\n",
        );
        totals(&mut s, run, CaseKind::Model);
    }
    s.push_str("</section>\n");
    super::signoff::html_na(&mut s, run);
    super::statements::html_map(&mut s, &run.statements);
    coverage(&mut s, run);
    super::statements::html(&mut s, &run.statements);
    if let Some(m) = &run.mutation {
        let _ = writeln!(
            s,
            "<section id=\"mutation\"><h2>Mutation score</h2>\n<p>{}: one datum the manuals state changed at a time (<code>harness mutants</code>).</p></section>",
            text(&m.to_string())
        );
    }
    errata(&mut s, run);
    s.push_str("<section id=\"record-section\"><h2>Record</h2>\n");
    record_table(&mut s, run);
    s.push_str("</section>\n");
    let _ = write!(s, "<script>{SCRIPT}</script>\n</body></html>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::fixtures::sample_run;

    fn page() -> String {
        render(&sample_run())
    }

    #[test]
    fn the_mutation_score_is_shown_where_harness_mutants_measured_it() {
        assert!(page().contains("<section id=\"mutation\"><h2>Mutation score</h2>\n<p>mutation score: 962 of 1000 mutants of the manuals as code killed (96.2 %), measured 2026-11-27T05:00:00Z: one datum"));
        let mut run = sample_run();
        run.mutation = None;
        assert!(!render(&run).contains("id=\"mutation\""));
    }

    #[test]
    fn the_verdict_comes_first_then_motion_then_the_failures_then_the_tables() {
        let h = page();
        let at = |needle: &str| h.find(needle).unwrap_or_else(|| panic!("{needle}\n{h}"));
        let banner = at("<div id=\"overall\" class=\"overall-fail\" data-overall=\"FAIL\">");
        assert_eq!(
            banner,
            at("<body>\n") + "<body>\n".len(),
            "first in the body"
        );
        let motion = at(
            "<p id=\"motion\" class=\"motion-no\">Motion not allowed (--allow-motion not given)",
        );
        let failures = at("<section id=\"cases\">");
        let tables = at("<section id=\"totals\">");
        assert!(banner < motion && motion < at("<h1>"), "{h}");
        assert!(motion < failures && failures < tables, "{h}");
        for later in [
            "<section id=\"not-applicable\">",
            "<section id=\"coverage-map\">",
            "<section id=\"coverage\">",
            "<section id=\"statements\">",
            "<section id=\"errata\">",
            "<table id=\"record\">",
        ] {
            assert!(tables < at(later), "{later}");
        }
        assert!(
            h.contains(
                "<tr><th>identity sk550p</th><td>NORD SK 550P, firmware V1.2 R0, serial 123456"
            ),
            "{h}"
        );
        assert!(
            h.contains(
                "<tr><th>command line</th><td>harness run --filter &apos;a b&apos;</td></tr>"
            ),
            "{h}"
        );
    }

    #[test]
    fn totals_keep_device_and_model_apart() {
        let h = page();
        assert!(
            h.contains(
                "<td class=\"n v-pass nz\" data-verdict=\"pass\" id=\"total-device-pass\">1</td>"
            ),
            "{h}"
        );
        assert!(
            h.contains(
                "<td class=\"n v-pass nz\" data-verdict=\"pass\" id=\"total-model-pass\">1</td>"
            ),
            "{h}"
        );
        let model = &h[h.find("id=\"totals-model\"").unwrap()..];
        let model = &model[..model.find("</table>").unwrap()];
        assert!(model.contains("data-profile=\"sk550p\""), "{model}");
        assert!(!model.contains("data-profile=\"tu3-eip\""), "{model}");
    }

    #[test]
    fn each_profile_has_a_verdict_bar_of_what_ran() {
        let h = page();
        // tu3-eip: one error, one inconclusive, one not applicable (not in the bar).
        assert!(
            h.contains("<td><span class=\"vbar\" title=\"0 pass, 0 fail, 1 inconclusive, 1 error; 1 not applicable\"><i class=\"v-inconclusive\" style=\"flex-grow:1\"></i><i class=\"v-error\" style=\"flex-grow:1\"></i></span></td></tr>"),
            "{h}"
        );
        // sk550p: a pass and a fail.
        assert!(
            h.contains("<span class=\"vbar\" title=\"1 pass, 1 fail, 0 inconclusive, 0 error; 0 not applicable\"><i class=\"v-pass\" style=\"flex-grow:1\"></i><i class=\"v-fail\" style=\"flex-grow:1\"></i></span>"),
            "{h}"
        );
        // Bars carry no data-verdict: the counts stay the table cells'.
        let bars = h.split("class=\"vbar\"").count() - 1;
        assert_eq!(
            bars,
            3 + 2,
            "device: 2 profiles and all; model: sk550p and all"
        );
        assert!(h.contains("<section id=\"coverage-map\">"), "{h}");
    }

    #[test]
    fn failing_cases_show_observed_required_clause_and_transcript() {
        let h = page();
        assert_eq!(
            h.matches("<article class=\"case").count(),
            3,
            "fail, error, inconclusive"
        );
        let fail = &h[h.find("data-verdict=\"fail\" data-doc").unwrap()..];
        let fail = &fail[..fail.find("</article>").unwrap()];
        assert!(
            fail.contains("<dt>manual</dt><dd>BU 0620 (2020-03 en) §2.2.7 p. 20</dd>"),
            "{fail}"
        );
        assert!(
            fail.contains("<dt>required</dt><dd>title of bu0620/addressing/coe-p102</dd>"),
            "{fail}"
        );
        assert!(
            fail.contains(
                "<dt>observed</dt><dd>status: expected 2865 (0B31h), got 2871 (0B37h)</dd>"
            ),
            "{fail}"
        );
        assert!(fail.contains("<dt>step observed</dt><dd><code>{&quot;ak&quot;:1,&quot;pwe&quot;:250}</code></dd>"), "{fail}");
        assert!(
            fail.contains(&format!(
                "<pre>{}</pre>",
                text(&transcript::render(&sample_run().cases[1]))
            )),
            "{fail}"
        );
        // Passing and not applicable cases are counted, not listed.
        assert!(!h.contains("data-verdict=\"pass\" data-doc"), "{h}");
    }

    #[test]
    fn coverage_filters_and_errata() {
        let h = page();
        assert!(h.contains("<tr data-doc=\"BU 0620\" data-pass=\"1\" data-fail=\"0\" data-inconclusive=\"0\" data-error=\"0\" data-not_applicable=\"0\"><td>BU 0620</td><td>2020-03 en</td><td>2.6.1</td><td class=\"n\">0</td>"), "{h}");
        assert!(h.contains("<td class=\"n\">1/1</td></tr>"), "{h}");
        assert!(
            h.contains("<option value=\"BU 2100\">BU 2100</option>"),
            "{h}"
        );
        assert!(
            h.contains("<td><code>class 103</code></td><td><code>class 102</code></td>"),
            "{h}"
        );
    }

    #[test]
    fn self_contained_and_escaped() {
        let mut run = sample_run();
        run.cases[1].message = "<script>alert(1)</script>".into();
        let h = render(&run);
        assert!(!h.contains("<script>alert"), "{h}");
        assert!(h.contains("&lt;script&gt;alert(1)&lt;/script&gt;"), "{h}");
        for external in ["src=\"http", "href=\"http", "<link", "@import", "url("] {
            assert!(!h.contains(external), "{external}");
        }
        assert_eq!(h.matches("<script>").count(), 1, "one inline script");
    }
}
