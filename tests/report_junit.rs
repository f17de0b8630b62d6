//! `junit.xml` of a run with a pass, a fail, a model check, not applicable cases and a suite
//! file that did not load, validated with `xmllint --schema` against the Jenkins xunit
//! plugin's JUnit schema and the stricter Ant JUnit schema (`tests/schemas/README.md` says where
//! they come from and what each demands). Needs xmllint (libxml2-utils, `.ci/interop-setup`):
//! skips without it on a developer's machine, fails under CI.

use std::path::{Path, PathBuf};
use std::process::Command;

// The two helpers alone, not `common/mod.rs`, whose network helpers these tests do not use.
#[path = "common/peer.rs"]
mod peer;
#[path = "common/report_run.rs"]
mod report_run;
use peer::{require_or_skip, runs};
use report_run::{read, report_run};

fn schema(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/schemas")
        .join(name)
}

/// `xmllint --schema`: `Ok` when the document validates, else xmllint's complaint.
fn validate(xsd: &Path, doc: &Path) -> Result<(), String> {
    let o = Command::new("xmllint")
        .args(["--noout", "--schema"])
        .arg(xsd)
        .arg(doc)
        .output()
        .expect("xmllint runs");
    if o.status.success() {
        Ok(())
    } else {
        Err(String::from_utf8_lossy(&o.stderr).into_owned())
    }
}

/// The sum of one attribute over the `<testsuite>` elements.
fn suite_sum(xml: &str, attr: &str) -> usize {
    xml.split("<testsuite ")
        .skip(1)
        .map(|t| {
            let tag = &t[..t.find('>').unwrap()];
            tag.split(&format!(" {attr}=\""))
                .nth(1)
                .and_then(|v| v.split('"').next())
                .unwrap_or_else(|| panic!("no {attr} in <testsuite {tag}>"))
                .parse::<usize>()
                .unwrap()
        })
        .sum()
}

#[test]
fn junit_validates_against_the_jenkins_and_ant_schemas() {
    let why = "JUnit XML against the Jenkins xunit and Ant schemas";
    if !require_or_skip(
        runs("xmllint", "--version"),
        "xmllint (libxml2-utils; bash .ci/interop-setup installs it)",
        why,
    ) {
        return;
    }
    let run = report_run("report-junit");
    let junit = run.out.join("junit.xml");
    let xml = read(&junit);

    // The file as written, against both schemas.
    validate(&schema("jenkins-xunit-junit-10.xsd"), &junit)
        .unwrap_or_else(|e| panic!("Jenkins xunit schema: {e}\n{xml}"));
    validate(&schema("ant-junit.xsd"), &junit)
        .unwrap_or_else(|e| panic!("Ant JUnit schema: {e}\n{xml}"));

    // A broken document does not validate: the checks can fail. Ant's schema refuses any
    // attribute on the root (what junit.xml used to have), both a misspelt one on a suite.
    let broken = run.out.join("junit-broken.xml");
    std::fs::write(&broken, xml.replacen(" tests=\"", " tezts=\"", 1)).unwrap();
    assert!(validate(&schema("jenkins-xunit-junit-10.xsd"), &broken).is_err());
    assert!(validate(&schema("ant-junit.xsd"), &broken).is_err());
    std::fs::write(
        &broken,
        xml.replacen("<testsuites>", "<testsuites name=\"harness run\">", 1),
    )
    .unwrap();
    assert!(validate(&schema("ant-junit.xsd"), &broken).is_err());

    // What the document says agrees with the run.
    let cases = run.json["cases"].as_array().unwrap();
    let count = |v: &str| cases.iter().filter(|c| c["verdict"] == v).count();
    let load_errors = run.json["load_errors"].as_array().unwrap().len();
    assert_eq!(load_errors, 1, "{}", run.json["load_errors"]);
    assert!(
        xml.contains("\n<testsuites>\n  <testsuite id=\"0\""),
        "{xml}"
    );
    assert_eq!(
        (
            suite_sum(&xml, "tests"),
            suite_sum(&xml, "failures"),
            suite_sum(&xml, "errors")
        ),
        (
            cases.len() + load_errors,
            count("fail"),
            count("error") + load_errors
        ),
        "{xml}"
    );
    assert_eq!(run.json["counts"]["fail"], 1, "{}", run.json);
    assert_eq!(run.json["counts_model"]["fail"], 1, "{}", run.json);
    // Device and model suites per profile, and the suite files that did not load.
    for suite in [
        "name=\"tu3-pnt\" package=\"tu3-pnt\"",
        "name=\"tu3-pnt model\" package=\"tu3-pnt.model\"",
        "name=\"sk550p\" package=\"sk550p\"",
        "name=\"sk550p model\" package=\"sk550p.model\"",
        "name=\"suite files\" package=\"suite files\" tests=\"1\" failures=\"0\" errors=\"1\"",
    ] {
        assert!(xml.contains(suite), "{suite}\n{xml}");
    }
    assert!(
        xml.contains("<testcase name=\"bu0590/report-test/p172-wrong\" classname=\"tu3-pnt.BU 0590 §5\u{2024}1\u{2024}3\""),
        "{xml}"
    );
    let broken_file = run.json["load_errors"][0].as_str().unwrap();
    let place = broken_file.split_once(": ").unwrap().0;
    assert!(place.contains("broken.yaml:"), "file and line: {place}");
    assert!(
        xml.contains(&format!(
            "<testcase name=\"{place}\" classname=\"suite files\""
        )),
        "{xml}"
    );
    // Every (classname, name) pair is distinct.
    let mut pairs: Vec<(&str, &str)> = xml
        .split("<testcase name=\"")
        .skip(1)
        .map(|t| {
            let (name, rest) = t.split_once('"').unwrap();
            let class = rest
                .split("classname=\"")
                .nth(1)
                .unwrap()
                .split('"')
                .next()
                .unwrap();
            (class, name)
        })
        .collect();
    let n = pairs.len();
    assert_eq!(n, cases.len() + load_errors);
    pairs.sort_unstable();
    pairs.dedup();
    assert_eq!(pairs.len(), n, "duplicate (classname, name) pairs");
    let _ = std::fs::remove_dir_all(run.out.parent().unwrap());
}
