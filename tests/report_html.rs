//! `index.html` in a real browser: headless Chromium (Debian's package, `.ci/interop-setup`)
//! loads the report of a run with a failure from its `file://` URL and dumps the DOM after the
//! page's script ran. Proves that the page loads without console errors, that its self-check
//! (the numbers shown agree with each other) passed, that the counts shown are the run's
//! counts, and that the verdict and manual filters, read from the URL fragment, hide what
//! they should. Skips without Chromium on a developer's machine, fails under CI.

use serde_json::Value;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

// The two helpers alone, not `common/mod.rs`, whose network helpers these tests do not use.
#[path = "common/peer.rs"]
mod peer;
#[path = "common/report_run.rs"]
mod report_run;
use peer::{is_root, require_or_skip};
use report_run::report_run;

const VERDICTS: [&str; 5] = ["pass", "fail", "inconclusive", "error", "not_applicable"];

fn chromium() -> Option<&'static str> {
    ["chromium", "chromium-browser"].into_iter().find(|b| {
        Command::new(b)
            .arg("--version")
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success())
    })
}

/// The page's DOM after load, and Chromium's log (console messages show as `:CONSOLE` lines).
fn dump_dom(browser: &str, page: &Path, fragment: &str, profile_dir: &Path) -> (String, String) {
    let url = format!("file://{}{fragment}", page.display());
    let mut cmd = Command::new(browser);
    cmd.args([
        "--headless",
        "--disable-gpu",
        "--enable-logging=stderr",
        "--v=0",
    ])
    .arg(format!("--user-data-dir={}", profile_dir.display()))
    .args(["--dump-dom", &url])
    .stdout(Stdio::piped())
    .stderr(Stdio::piped());
    if is_root() {
        // Chromium refuses to run as root with its sandbox.
        cmd.arg("--no-sandbox");
    }
    let child = cmd.spawn().expect("chromium starts");
    let id = child.id();
    // Bounded: a browser that hangs fails the test instead of the CI run.
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(child.wait_with_output());
    });
    let deadline = Instant::now() + Duration::from_secs(120);
    let o = loop {
        if let Ok(o) = rx.try_recv() {
            break o.expect("chromium ran");
        }
        if Instant::now() > deadline {
            let _ = Command::new("kill").arg(id.to_string()).status();
            panic!("chromium did not finish {url} within 120 s");
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    assert!(
        o.status.success(),
        "chromium: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// The number in the element with `id`.
fn number(dom: &str, id: &str) -> u64 {
    let at = dom
        .find(&format!("id=\"{id}\""))
        .unwrap_or_else(|| panic!("no #{id} in the page"));
    let text = &dom[at..];
    let text = &text[text.find('>').unwrap() + 1..];
    text[..text.find('<').unwrap()]
        .trim()
        .parse()
        .unwrap_or_else(|e| panic!("#{id}: {e}"))
}

/// The counts of `profile`'s row in the totals table `table` (`totals-device`), by verdict.
fn row_counts(dom: &str, table: &str, profile: &str) -> Vec<(String, u64)> {
    let t = &dom[dom.find(&format!("id=\"{table}\"")).unwrap()..];
    let t = &t[..t.find("</table>").unwrap()];
    let row = &t[t
        .find(&format!("data-profile=\"{profile}\""))
        .unwrap_or_else(|| panic!("no {profile} row in {table}"))..];
    let row = &row[..row.find("</tr>").unwrap()];
    row.split("data-verdict=\"")
        .skip(1)
        .map(|c| {
            let (v, rest) = c.split_once('"').unwrap();
            let n = &rest[rest.find('>').unwrap() + 1..rest.find('<').unwrap()];
            (v.to_string(), n.parse().unwrap())
        })
        .collect()
}

/// The opening tags of the listed cases: (verdict, doc, hidden).
fn case_tags(dom: &str) -> Vec<(String, String, bool)> {
    dom.split("<article ")
        .skip(1)
        .map(|t| {
            let tag = &t[..t.find('>').unwrap()];
            let attr = |name: &str| {
                tag.split(&format!("{name}=\""))
                    .nth(1)
                    .and_then(|r| r.split('"').next())
                    .unwrap_or_default()
                    .to_string()
            };
            (
                attr("data-verdict"),
                attr("data-doc"),
                tag.contains(" hidden"),
            )
        })
        .collect()
}

fn assert_no_console_messages(log: &str) {
    let console: Vec<&str> = log
        .lines()
        .filter(|l| l.contains(":CONSOLE") || l.contains("Uncaught"))
        .collect();
    assert!(console.is_empty(), "console messages: {console:#?}");
}

#[test]
fn html_report_loads_counts_and_filters_in_headless_chromium() {
    let why = "the HTML report in a headless browser";
    let browser = chromium();
    if !require_or_skip(
        browser.is_some(),
        "chromium (Debian package; bash .ci/interop-setup installs it)",
        why,
    ) {
        return;
    }
    let browser = browser.unwrap();
    let run = report_run("report-html");
    let page = run.out.join("index.html");
    let profile_dir = run.out.join("chromium-profile");
    let json: &Value = &run.json;
    assert_eq!(json["counts"]["fail"], 1, "the run has a failure: {json}");

    // Unfiltered: no console message, the self-check passed, the counts are the run's.
    let (dom, log) = dump_dom(browser, &page, "", &profile_dir);
    assert_no_console_messages(&log);
    assert!(
        dom.contains("<output id=\"selfcheck\" data-ok=\"true\">self-check ok</output>"),
        "self-check: {}",
        &dom[dom.find("id=\"selfcheck\"").unwrap_or(0)..][..200]
    );
    for v in VERDICTS {
        assert_eq!(
            number(&dom, &format!("total-device-{v}")),
            json["counts"][v].as_u64().unwrap(),
            "device {v}"
        );
        assert_eq!(
            number(&dom, &format!("total-model-{v}")),
            json["counts_model"][v].as_u64().unwrap(),
            "model {v}"
        );
    }
    for (table, key) in [
        ("totals-device", "counts_by_profile"),
        ("totals-model", "counts_model_by_profile"),
    ] {
        for profile in ["tu3-pnt", "sk550p"] {
            let want: Vec<(String, u64)> = VERDICTS
                .iter()
                .map(|v| (v.to_string(), json[key][profile][*v].as_u64().unwrap()))
                .collect();
            assert_eq!(row_counts(&dom, table, profile), want, "{table} {profile}");
        }
    }
    let cases = case_tags(&dom);
    let listed =
        |v: &str| json["counts"][v].as_u64().unwrap() + json["counts_model"][v].as_u64().unwrap();
    assert_eq!(
        cases.len() as u64,
        listed("fail") + listed("error") + listed("inconclusive")
    );
    assert!(
        cases.iter().all(|c| !c.2),
        "nothing hidden without a filter"
    );
    assert!(
        dom.contains("id=\"load-errors\""),
        "the load error is shown"
    );
    // The overall verdict comes first: a suite file did not load, so the run is incomplete;
    // then the failures, then the tables.
    let body = dom[dom.find("<body>").unwrap() + "<body>".len()..].trim_start();
    assert!(
        body.starts_with(
            "<div id=\"overall\" class=\"overall-incomplete\" data-overall=\"INCOMPLETE\">"
        ),
        "{}",
        &body[..300.min(body.len())]
    );
    let at = |id: &str| {
        dom.find(&format!("id=\"{id}\""))
            .unwrap_or_else(|| panic!("#{id}"))
    };
    assert!(at("cases") < at("totals") && at("totals") < at("not-applicable"));
    // The not-applicable cases by reason: sk550p's two device cases are about tu3-pnt.
    assert!(
        dom.contains("<tr data-reason=\"Product\" data-n=\"2\"><td>another product</td>"),
        "{}",
        &dom[at("not-applicable")..][..600]
    );
    assert!(
        // The embedded simulator: no limits apply, and the line says so.
        dom.contains("<p id=\"motion\" class=\"motion-yes\">No motor, no EEPROM"),
        "the motion line"
    );

    // Filtered by the URL fragment: only failing cases of BU 0590 stay visible, and the
    // coverage keeps only sections with a failure.
    let (dom, log) = dump_dom(
        browser,
        &page,
        "#verdict=fail&manual=BU%200590",
        &profile_dir,
    );
    assert_no_console_messages(&log);
    assert!(
        dom.contains("data-ok=\"true\""),
        "self-check under a filter"
    );
    let cases = case_tags(&dom);
    let visible: Vec<_> = cases.iter().filter(|c| !c.2).collect();
    assert_eq!(visible.len() as u64, listed("fail"), "{cases:?}");
    assert!(
        visible.iter().all(|c| c.0 == "fail" && c.1 == "BU 0590"),
        "{cases:?}"
    );
    assert!(
        dom.contains(&format!("data-shown=\"{}\"", listed("fail"))),
        "the count of shown cases"
    );
    let coverage = &dom[dom.find("<section id=\"coverage\"").unwrap()..];
    let rows: Vec<&str> = coverage.split("<tr data-doc=").skip(1).collect();
    assert!(!rows.is_empty());
    for row in rows {
        let tag = &row[..row.find('>').unwrap()];
        assert_eq!(
            tag.contains(" hidden"),
            tag.contains("data-fail=\"0\""),
            "coverage row {tag}"
        );
    }

    // A filter with nothing to show hides every case.
    let (dom, _) = dump_dom(browser, &page, "#verdict=error", &profile_dir);
    assert!(case_tags(&dom).iter().all(|c| c.2));

    // The self-check can fail: a page whose total disagrees with its rows says so.
    let html = std::fs::read_to_string(&page).unwrap();
    let pass = json["counts"]["pass"].as_u64().unwrap();
    let cell = format!("id=\"total-device-pass\">{pass}<");
    assert!(html.contains(&cell), "{cell}");
    let tampered = run.out.join("tampered.html");
    std::fs::write(
        &tampered,
        html.replace(&cell, &format!("id=\"total-device-pass\">{}<", pass + 7)),
    )
    .unwrap();
    let (dom, _) = dump_dom(browser, &tampered, "", &profile_dir);
    assert!(
        dom.contains("data-ok=\"false\">self-check failed: device pass: profiles sum to"),
        "{}",
        &dom[dom.find("id=\"selfcheck\"").unwrap()..][..300]
    );
    // And so does one whose reasons do not add up to the not applicable cases.
    std::fs::write(
        &tampered,
        html.replace(
            "data-reason=\"Product\" data-n=\"2\"",
            "data-reason=\"Product\" data-n=\"3\"",
        ),
    )
    .unwrap();
    let (dom, _) = dump_dom(browser, &tampered, "", &profile_dir);
    assert!(
        dom.contains("data-ok=\"false\">self-check failed: not applicable by reason: 3, totals 2"),
        "{}",
        &dom[dom.find("id=\"selfcheck\"").unwrap()..][..300]
    );
    let _ = std::fs::remove_dir_all(run.out.parent().unwrap());
}
