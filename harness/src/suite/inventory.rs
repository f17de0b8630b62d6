//! The statement inventories: `suites/inventory/<manual>.yaml`, one per manual file, listing
//! every testable statement of the manual section by section, each with the ids of the cases
//! that assert it, or `untestable:` with the reason, or `pending:` with the bus whose binding
//! is not there yet (an entry with none of them is testable and not asserted yet: the gap).
//!
//! An asserted statement's `values:` name, for each value it states, the case and step whose
//! expectation carries it (`{ case, step, value }`, steps counted from 1 as the transcripts
//! count them): a claim the loader can check ([`super::claim`]). A statement that names cases
//! without values is refused: a case that merely touches the topic asserts nothing.
//!
//! Its `contents:` list the manual's whole table of contents (front matter and index
//! included), so that "every section" can be checked: each statement lies in a listed section,
//! and a listed section in which no statement lies says why with `nothing:` (a heading, a
//! safety note, an index), so a forgotten section cannot pass for an empty one.
//!
//! [`coverage`] counts them per manual and section (`harness coverage`, the run's summary and
//! HTML report); [`check`] keeps an inventory honest against the loaded suites: every case id
//! it names exists, every value is carried by the step it names, every case citing an
//! inventoried manual is named by a statement, and the asserted statements of a manual do not
//! fall below the floor checked in beside them (`floors.yaml`), so the count can only grow.

use serde::Deserialize;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use super::claim::carries;
use super::load::{LoadError, Loaded};
use crate::notation::Matcher;
use crate::outcome::{CaseKind, SectionCount, StatementCoverage};

/// The folder below the suites that holds the inventories (the suite loader skips it).
pub(crate) const DIR: &str = "inventory";

/// The floors file in [`DIR`]: per manual (`"<doc> <edition>"`), the fewest asserted
/// statements allowed.
const FLOORS: &str = "floors.yaml";

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct FileDoc {
    doc: String,
    edition: String,
    contents: Vec<SectionDoc>,
    statements: Vec<StatementDoc>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SectionDoc {
    section: String,
    title: String,
    #[serde(default)]
    nothing: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct StatementDoc {
    section: String,
    #[serde(default)]
    page: Option<u32>,
    says: String,
    #[serde(default)]
    cases: Vec<String>,
    #[serde(default)]
    values: Vec<ValueDoc>,
    #[serde(default)]
    untestable: Option<String>,
    #[serde(default)]
    pending: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ValueDoc {
    case: String,
    step: usize,
    value: serde_json::Value,
}

/// One value of a statement and the step whose expectation carries it.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Carrier {
    /// The case's full id, one of the statement's cases.
    pub(crate) case: String,
    /// The step, from 1.
    pub(crate) step: usize,
    /// The value, parsed as an expectation is.
    pub(crate) value: Matcher,
    /// As written, for messages.
    pub(crate) text: String,
}

/// Where a statement stands.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Status {
    /// These cases assert it.
    Asserted(Vec<String>),
    /// No case can: the reason (hardware only, needs a PLC tool).
    Untestable(String),
    /// Its bus's binding is not there yet.
    Pending(String),
    /// Testable, and no case asserts it yet.
    Open,
}

/// One testable statement of a manual.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Statement {
    pub(crate) section: String,
    pub(crate) page: Option<u32>,
    pub(crate) says: String,
    pub(crate) status: Status,
    /// Its values and the steps that carry them (an asserted statement has at least one).
    pub(crate) values: Vec<Carrier>,
}

/// One section of a manual's table of contents.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Section {
    /// Its number (`2.5.6.4`), or for an unnumbered one (the index) its title.
    pub(crate) section: String,
    /// As the table of contents prints it.
    pub(crate) title: String,
    /// Why no testable statement lies in it; only for a section without statements.
    pub(crate) nothing: Option<String>,
}

impl Section {
    /// Whether a statement citing `section` lies in this one: the same number or one below
    /// it (`2.5` holds `2.5.6.4`, not `2.50`).
    fn holds(&self, section: &str) -> bool {
        section
            .strip_prefix(self.section.as_str())
            .is_some_and(|rest| rest.is_empty() || rest.starts_with('.'))
    }
}

/// One manual's inventory.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Inventory {
    pub(crate) file: PathBuf,
    pub(crate) doc: String,
    pub(crate) edition: String,
    /// The manual's table of contents, in its order.
    pub(crate) contents: Vec<Section>,
    pub(crate) statements: Vec<Statement>,
}

impl Inventory {
    /// `BU 0620 2020-03 en`: the manual as the floors and messages name it.
    pub(crate) fn manual(&self) -> String {
        format!("{} {}", self.doc, self.edition)
    }
}

fn error(file: &Path, line: Option<u64>, message: String) -> LoadError {
    LoadError {
        file: file.to_path_buf(),
        line,
        message,
    }
}

fn parse<T: for<'de> Deserialize<'de>>(file: &Path, text: &str) -> Result<T, LoadError> {
    serde_saphyr::from_str(text).map_err(|e| {
        let line = e.location().map(|l| l.line());
        let first = e.to_string();
        error(
            file,
            line,
            first.lines().next().unwrap_or("invalid YAML").to_string(),
        )
    })
}

/// Reads one inventory; a statement with more than one status is an error naming it.
pub(crate) fn parse_inventory(file: &Path, text: &str) -> Result<Inventory, LoadError> {
    let doc: FileDoc = parse(file, text)?;
    let mut statements = Vec::with_capacity(doc.statements.len());
    for s in doc.statements {
        let status = match (s.cases.is_empty(), s.untestable, s.pending) {
            (false, None, None) => Status::Asserted(s.cases),
            (true, Some(why), None) => Status::Untestable(why),
            (true, None, Some(bus)) => Status::Pending(bus),
            (true, None, None) => Status::Open,
            _ => {
                return Err(error(
                    file,
                    None,
                    format!(
                        "§{} \"{}\": give one of `cases`, `untestable`, `pending`",
                        s.section, s.says
                    ),
                ))
            }
        };
        let values: Vec<Carrier> = s
            .values
            .into_iter()
            .map(|v| carrier(v, &status))
            .collect::<Result<_, String>>()
            .map_err(|e| error(file, None, format!("§{} \"{}\": {e}", s.section, s.says)))?;
        if matches!(status, Status::Asserted(_)) && values.is_empty() {
            return Err(error(
                file,
                None,
                format!(
                    "§{} \"{}\": names cases but no `values`: name the step whose expectation carries each value it states",
                    s.section, s.says
                ),
            ));
        }
        statements.push(Statement {
            section: s.section,
            page: s.page,
            says: s.says,
            status,
            values,
        });
    }
    let contents: Vec<Section> = doc
        .contents
        .into_iter()
        .map(|c| Section {
            section: c.section,
            title: c.title,
            nothing: c.nothing,
        })
        .collect();
    check_contents(&contents, &statements).map_err(|e| error(file, None, e))?;
    Ok(Inventory {
        file: file.to_path_buf(),
        doc: doc.doc,
        edition: doc.edition,
        contents,
        statements,
    })
}

/// Holds the statements against the table of contents: a section listed once, every
/// statement in a listed section, and `nothing:` exactly on the sections no statement lies
/// in (one on a section with statements is stale: the section has something testable now).
fn check_contents(contents: &[Section], statements: &[Statement]) -> Result<(), String> {
    let mut seen = BTreeSet::new();
    for c in contents {
        if !seen.insert(c.section.as_str()) {
            return Err(format!(
                "`contents`: §{} \"{}\" is listed twice",
                c.section, c.title
            ));
        }
    }
    if let Some(s) = statements
        .iter()
        .find(|s| !contents.iter().any(|c| c.holds(&s.section)))
    {
        return Err(format!(
            "§{} \"{}\": no section of `contents` holds it: list the section as the manual's table of contents prints it",
            s.section, s.says
        ));
    }
    for c in contents {
        let inside = statements.iter().filter(|s| c.holds(&s.section)).count();
        match (&c.nothing, inside) {
            (None, 0) => {
                return Err(format!(
                    "`contents`: §{} \"{}\": no statement lies in it: add the statements it makes, or `nothing:` with why it makes none",
                    c.section, c.title
                ))
            }
            (Some(why), 0) if why.trim().is_empty() => {
                return Err(format!(
                    "`contents`: §{} \"{}\": `nothing:` gives no reason: say why it states nothing testable",
                    c.section, c.title
                ))
            }
            (Some(_), n) if n > 0 => {
                return Err(format!(
                    "`contents`: §{} \"{}\": `nothing:` though {n} statement(s) lie in it: drop the stale `nothing:`",
                    c.section, c.title
                ))
            }
            _ => {}
        }
    }
    Ok(())
}

/// A manual's sections counted: listed in its table of contents, holding statements, and
/// with nothing testable (`nothing:`, the reason given). [`check_contents`] makes the last
/// two add up to the first.
pub(crate) fn sections(inventories: &[Inventory]) -> Vec<SectionCount> {
    inventories
        .iter()
        .map(|inv| {
            let nothing = inv.contents.iter().filter(|c| c.nothing.is_some()).count();
            SectionCount {
                doc: inv.doc.clone(),
                edition: inv.edition.clone(),
                contents: inv.contents.len(),
                with_statements: inv.contents.len() - nothing,
                nothing,
            }
        })
        .collect()
}

/// One `values:` entry: its case must be one the statement names, its step counted from 1,
/// its value written as an expectation is.
fn carrier(v: ValueDoc, status: &Status) -> Result<Carrier, String> {
    let Status::Asserted(cases) = status else {
        return Err("`values` name the steps of the statement's `cases`; it has none".into());
    };
    if !cases.contains(&v.case) {
        return Err(format!(
            "a value names case `{}`, which is not among its `cases`",
            v.case
        ));
    }
    if v.step == 0 {
        return Err(format!("case `{}`: steps count from 1", v.case));
    }
    let text = match &v.value {
        serde_json::Value::String(t) => t.clone(),
        other => other.to_string(),
    };
    let value = Matcher::parse(&v.value).map_err(|e| format!("value `{text}`: {e}"))?;
    Ok(Carrier {
        case: v.case,
        step: v.step,
        value,
        text,
    })
}

/// Every inventory in `<suites>/inventory/` (none when the folder is missing), by file name.
pub(crate) fn load(suites: &Path) -> Result<Vec<Inventory>, LoadError> {
    let dir = suites.join(DIR);
    let Ok(entries) = std::fs::read_dir(&dir) else {
        return Ok(Vec::new());
    };
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("yaml"))
                && p.file_name().is_some_and(|n| n != FLOORS)
        })
        .collect();
    files.sort();
    files
        .iter()
        .map(|f| {
            let text = std::fs::read_to_string(f).map_err(|e| error(f, None, e.to_string()))?;
            parse_inventory(f, &text)
        })
        .collect()
}

/// The floors: manual → fewest asserted statements.
pub(crate) fn floors(suites: &Path) -> Result<BTreeMap<String, usize>, LoadError> {
    let file = suites.join(DIR).join(FLOORS);
    match std::fs::read_to_string(&file) {
        Ok(text) => parse(&file, &text),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(BTreeMap::new()),
        Err(e) => Err(error(&file, None, e.to_string())),
    }
}

/// Sort key for section numbers: numerically per level.
fn section_key(s: &str) -> Vec<(u64, &str)> {
    s.split('.')
        .map(|p| p.parse().map_or((u64::MAX, p), |n| (n, "")))
        .collect()
}

/// The statements counted per manual and section, in manual then section order. A statement
/// counts as asserted on the device when one of its cases in `loaded` reaches the DUT (see
/// [`crate::suite::Case::kind`]); one only reference-model cases assert is model-only.
pub(crate) fn coverage(inventories: &[Inventory], loaded: &Loaded) -> Vec<StatementCoverage> {
    let device: BTreeSet<&str> = loaded
        .cases
        .iter()
        .filter(|c| c.kind() == CaseKind::Device)
        .map(|c| c.id.as_str())
        .collect();
    let mut out: Vec<StatementCoverage> = Vec::new();
    for inv in inventories {
        let mut by: BTreeMap<(Vec<(u64, &str)>, &str), StatementCoverage> = BTreeMap::new();
        for s in &inv.statements {
            let c = by
                .entry((section_key(&s.section), s.section.as_str()))
                .or_insert_with(|| StatementCoverage {
                    doc: inv.doc.clone(),
                    edition: inv.edition.clone(),
                    section: s.section.clone(),
                    ..StatementCoverage::default()
                });
            c.statements += 1;
            match s.status {
                Status::Asserted(ref cases)
                    if cases.iter().any(|id| device.contains(id.as_str())) =>
                {
                    c.asserted += 1
                }
                Status::Asserted(_) => c.model_only += 1,
                Status::Pending(_) => c.pending += 1,
                Status::Untestable(_) => c.untestable += 1,
                Status::Open => {}
            }
        }
        out.extend(by.into_values());
    }
    out
}

/// What keeps the inventories honest, as messages (none: all is well): case ids that do not
/// exist, a value the step it names does not carry, cases of an inventoried manual no
/// statement names, a manual whose asserted statements fell below its floor, a floor
/// for a manual without an inventory.
pub(crate) fn check(
    inventories: &[Inventory],
    loaded: &Loaded,
    floors: &BTreeMap<String, usize>,
) -> Vec<String> {
    let cases: BTreeMap<&str, &super::Case> =
        loaded.cases.iter().map(|c| (c.id.as_str(), c)).collect();
    let mut problems = Vec::new();
    for inv in inventories {
        let mut named = BTreeSet::new();
        let mut asserted = 0;
        for s in &inv.statements {
            let place = || format!("{}: §{} \"{}\"", inv.file.display(), s.section, s.says);
            if let Status::Asserted(ids) = &s.status {
                asserted += 1;
                for id in ids {
                    if !cases.contains_key(id.as_str()) {
                        problems.push(format!(
                            "{}: names case `{id}`, which no suite has",
                            place()
                        ));
                    }
                    named.insert(id.as_str());
                }
            }
            for v in &s.values {
                let Some(case) = cases.get(v.case.as_str()) else {
                    continue;
                };
                let expect = case.steps.get(v.step - 1).map(|step| step.expect.as_ref());
                let why = match expect {
                    None => format!("has {} steps", case.steps.len()),
                    Some(None) => format!("step {} expects nothing", v.step),
                    Some(Some(m)) if !carries(m, &v.value) => {
                        format!("step {}'s expectation `{m}` does not carry it", v.step)
                    }
                    Some(Some(_)) => continue,
                };
                problems.push(format!(
                    "{}: value `{}` is not asserted by case `{}` step {}: the case {why}",
                    place(),
                    v.text,
                    v.case,
                    v.step
                ));
            }
        }
        for c in loaded
            .cases
            .iter()
            .filter(|c| c.manual.doc == inv.doc && c.manual.edition == inv.edition)
        {
            if !named.contains(c.id.as_str()) {
                problems.push(format!(
                    "{}: case `{}` cites {} §{} and no statement names it",
                    inv.file.display(),
                    c.id,
                    inv.doc,
                    c.manual.section
                ));
            }
        }
        match floors.get(&inv.manual()) {
            Some(floor) if asserted < *floor => problems.push(format!(
                "{}: {asserted} asserted statements, fewer than the floor of {floor} (floors.yaml): the count may only grow",
                inv.manual()
            )),
            None => problems.push(format!(
                "{}: no floor in {DIR}/{FLOORS}",
                inv.manual()
            )),
            Some(_) => {}
        }
    }
    for manual in floors.keys() {
        if !inventories.iter().any(|i| &i.manual() == manual) {
            problems.push(format!("{DIR}/{FLOORS}: `{manual}` has no inventory"));
        }
    }
    problems
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::suite::load_text_for_tests;

    const INVENTORY: &str = r#"
doc: BU 0620
edition: "2020-03 en"
contents:
  - { section: "1", title: Introduction, nothing: "a heading" }
  - { section: "2.5", title: PROFINET IO basics }
  - { section: "2.5.6", title: Parameter data transmission }
  - { section: "4.2.5", title: CANopen }
  - { section: "6.1", title: Data transmission }
  - { section: Index, title: Index, nothing: "an index: page numbers" }
statements:
  - section: "2.5.6"
    page: 51
    says: P102 reads
    cases: [test/read]
    values: [{ case: test/read, step: 1, value: 250 }]
  - section: "2.5.6"
    says: P102 counts in 0.01 s
    cases: [test/resolution]
    values: [{ case: test/resolution, step: 1, value: 2 }]
  - section: "2.5.6"
    says: the LED is green
    untestable: "hardware: a colour"
  - section: "4.2.5"
    says: the system bus runs at 250 kBaud
    pending: can
  - section: "6.1.3"
    says: 047Eh makes the drive ready
"#;

    const SUITE: &str = r#"
doc: BU 0620
edition: "2020-03 en"
cases:
  - id: read
    title: read P102
    ref: { section: "2.5.6", page: 51 }
    steps:
      - read: { param: 102 }
        expect: { value: 250 }
  - id: resolution
    title: P102 resolution
    ref: { section: "2.5.6", page: 51 }
    steps:
      - { compute: params.def, args: { param: 102 }, expect: { decimals: 2 } }
  - id: process
    title: process data
    ref: { section: "6.1.3", page: 114 }
    steps:
      - process: { control: "047Eh", for: 40ms }
"#;

    fn inventory() -> Inventory {
        parse_inventory(Path::new("bu0620.yaml"), INVENTORY).unwrap()
    }

    #[test]
    fn statements_are_counted_per_section_device_and_model_apart() {
        let c = coverage(&[inventory()], &load_text_for_tests(SUITE));
        let sections: Vec<(&str, [usize; 6])> = c
            .iter()
            .map(|s| {
                (
                    s.section.as_str(),
                    [
                        s.statements,
                        s.asserted,
                        s.model_only,
                        s.pending,
                        s.untestable,
                        s.open(),
                    ],
                )
            })
            .collect();
        // §2.5.6: P102 read on the device, its resolution by the model only, the LED untestable.
        assert_eq!(
            sections,
            [
                ("2.5.6", [3, 1, 1, 0, 1, 0]),
                ("4.2.5", [1, 0, 0, 1, 0, 0]),
                ("6.1.3", [1, 0, 0, 0, 0, 1])
            ]
        );
        assert_eq!(c[0].testable(), 2);
        assert_eq!(c[0].device_percent(), Some(50.0));
        assert_eq!(c[0].percent(), Some(100.0));
        // Nothing testable: no share at all, rather than 100 %.
        assert_eq!((c[1].device_percent(), c[1].percent()), (None, None));
        assert_eq!(c[2].percent(), Some(0.0));
        // Without the suites no case is known to reach the device.
        let c = coverage(&[inventory()], &Loaded::default());
        assert_eq!((c[0].asserted, c[0].model_only), (0, 2));
    }

    #[test]
    fn the_p856_factory_value_is_asserted_on_the_device() {
        // The README's firmware comparison: "next" changes P856's factory value, so a device
        // case must assert it (a model case alone let the change through).
        let suites = Path::new(env!("CARGO_MANIFEST_DIR")).join("../suites");
        let loaded = crate::suite::load_dir(&suites, &crate::buses::vocabulary()).unwrap();
        for inv in load(&suites).unwrap() {
            for s in inv
                .statements
                .iter()
                .filter(|s| s.section == "4.2.2" && s.says.starts_with("P856 Addressing mode"))
            {
                let Status::Asserted(cases) = &s.status else {
                    panic!("{}: {} is not asserted", inv.manual(), s.says)
                };
                assert!(
                    loaded
                        .cases
                        .iter()
                        .any(|c| cases.contains(&c.id) && c.kind() == CaseKind::Device),
                    "{}: {} has no device case: {cases:?}",
                    inv.manual(),
                    s.says
                );
            }
        }
    }

    #[test]
    fn the_check_names_unknown_ids_unnamed_cases_and_a_fallen_floor() {
        let loaded = load_text_for_tests(SUITE);
        let floors: BTreeMap<String, usize> = [("BU 0620 2020-03 en".to_string(), 3)].into();
        let problems = check(&[inventory()], &loaded, &floors);
        // `process` cites BU 0620 and no statement names it (the 6.1.3 one is open); 2 asserted
        // is below the floor of 3.
        assert_eq!(problems.len(), 2, "{problems:?}");
        assert!(
            problems[0]
                .contains("case `test/process` cites BU 0620 §6.1.3 and no statement names it"),
            "{problems:?}"
        );
        assert!(
            problems[1].contains("fewer than the floor of 3"),
            "{problems:?}"
        );
        let wrong = parse_inventory(
            Path::new("x.yaml"),
            &INVENTORY
                .replace("[test/read]", "[nope]")
                .replace("case: test/read", "case: nope"),
        )
        .unwrap();
        let problems = check(&[wrong], &loaded, &BTreeMap::new());
        assert!(
            problems
                .iter()
                .any(|p| p.contains("names case `nope`, which no suite has")),
            "{problems:?}"
        );
        assert!(
            problems.iter().any(|p| p.contains("no floor")),
            "{problems:?}"
        );
    }

    /// The issue's own example of a hollow claim: P161 written, P186 read back. Its value is
    /// not in the step the claim names, and the check says so.
    const HOLLOW: &str = r#"
doc: BU 2100
edition: en
cases:
  - id: p161
    title: P161 read in at restart
    ref: { section: "5.1", page: 20 }
    steps:
      - write: { param: 161, element: 3, value: 0, target: interface }
      - read: { param: 186, element: 2, target: interface }
        expect: { value: 255 }
"#;

    fn hollow(values: &str) -> Vec<String> {
        let text = format!(
            "doc: BU 2100\nedition: en\ncontents: [{{ section: \"5\", title: Parameters }}]\nstatements:\n  - section: \"5.1\"\n    says: P161 [-03] = 0 is read in at restart\n    cases: [test/p161]\n    values: {values}\n"
        );
        let inv = parse_inventory(Path::new("bu2100.yaml"), &text).unwrap();
        let floors = [("BU 2100 en".to_string(), 0)].into();
        check(&[inv], &load_text_for_tests(HOLLOW), &floors)
    }

    #[test]
    fn a_value_the_named_step_does_not_carry_is_refused() {
        let p = hollow("[{ case: test/p161, step: 2, value: 0 }]");
        assert_eq!(p.len(), 1, "{p:?}");
        assert!(
            p[0].contains("value `0` is not asserted by case `test/p161` step 2")
                && p[0].contains("does not carry it"),
            "{p:?}"
        );
        // A step without an expectation carries nothing, nor does a step the case lacks.
        let p = hollow("[{ case: test/p161, step: 1, value: 0 }]");
        assert!(p[0].contains("step 1 expects nothing"), "{p:?}");
        let p = hollow("[{ case: test/p161, step: 3, value: 0 }]");
        assert!(p[0].contains("the case has 2 steps"), "{p:?}");
        // Made real, the claim holds.
        assert!(hollow("[{ case: test/p161, step: 2, value: 255 }]").is_empty());
    }

    #[test]
    fn values_name_the_statements_own_cases() {
        let text = INVENTORY.replace(
            "values: [{ case: test/resolution, step: 1, value: 2 }]",
            "values: [{ case: test/read, step: 1, value: 2 }]",
        );
        let e = parse_inventory(Path::new("x.yaml"), &text).unwrap_err();
        assert!(e.message.contains("not among its `cases`"), "{e}");
        let text = INVENTORY.replace("step: 1, value: 2", "step: 0, value: 2");
        let e = parse_inventory(Path::new("x.yaml"), &text).unwrap_err();
        assert!(e.message.contains("steps count from 1"), "{e}");
    }

    #[test]
    fn a_statement_naming_cases_without_values_is_refused() {
        let text = INVENTORY.replace(
            "    values: [{ case: test/read, step: 1, value: 250 }]\n",
            "",
        );
        let e = parse_inventory(Path::new("x.yaml"), &text).unwrap_err();
        assert!(
            e.message
                .contains("§2.5.6 \"P102 reads\": names cases but no `values`"),
            "{e}"
        );
    }

    #[test]
    fn a_statement_has_one_status_at_most() {
        let two = INVENTORY.replace(
            "    cases: [test/read]",
            "    cases: [test/read]\n    untestable: \"and this\"",
        );
        let e = parse_inventory(Path::new("x.yaml"), &two).unwrap_err();
        assert!(e.message.contains("give one of"), "{e}");
        let unknown = INVENTORY.replace("says: P102 reads", "says: P102 reads\n    said: x");
        let e = parse_inventory(Path::new("x.yaml"), &unknown).unwrap_err();
        assert!(e.line.is_some(), "{e}");
    }

    #[test]
    fn every_section_of_the_contents_holds_statements_or_says_why_not() {
        let e = |text: String| parse_inventory(Path::new("bu0620.yaml"), &text).unwrap_err();
        let counts = sections(&[inventory()]);
        assert_eq!(
            (
                counts[0].contents,
                counts[0].with_statements,
                counts[0].nothing
            ),
            (6, 4, 2)
        );
        // A statement outside the table of contents: §6.1 does not hold §6.10.
        let outside = e(INVENTORY.replace("section: \"6.1.3\"", "section: \"6.10\""));
        assert_eq!(outside.file, Path::new("bu0620.yaml"));
        assert!(
            outside.message.contains(
                "§6.10 \"047Eh makes the drive ready\": no section of `contents` holds it"
            ),
            "{outside}"
        );
        // A section without statements and without `nothing:`: forgotten, not empty.
        let forgotten = e(INVENTORY.replace(", nothing: \"a heading\"", ""));
        assert!(
            forgotten
                .message
                .contains("§1 \"Introduction\": no statement lies in it"),
            "{forgotten}"
        );
        // `nothing:` on a section that has statements (below it, too) is stale.
        let stale = e(INVENTORY.replace(
            "title: PROFINET IO basics }",
            "title: PROFINET IO basics, nothing: \"a heading\" }",
        ));
        assert!(
            stale.message.contains(
                "§2.5 \"PROFINET IO basics\": `nothing:` though 3 statement(s) lie in it"
            ),
            "{stale}"
        );
        let silent = e(INVENTORY.replace("nothing: \"a heading\"", "nothing: \" \""));
        assert!(
            silent
                .message
                .contains("§1 \"Introduction\": `nothing:` gives no reason"),
            "{silent}"
        );
        let twice = e(INVENTORY.replace(
            "  - { section: \"6.1\"",
            "  - { section: \"4.2.5\", title: CANopen }\n  - { section: \"6.1\"",
        ));
        assert!(
            twice.message.contains("§4.2.5 \"CANopen\" is listed twice"),
            "{twice}"
        );
        // The table of contents is required: without it no section can be checked.
        let none = e(INVENTORY.replace("contents:", "old_contents:"));
        assert!(none.line.is_some(), "{none}");
    }

    #[test]
    fn the_checked_in_inventories_are_honest() {
        let suites = Path::new(env!("CARGO_MANIFEST_DIR")).join("../suites");
        let loaded = crate::suite::load_dir(&suites, &crate::buses::vocabulary()).unwrap();
        let inventories = load(&suites).unwrap();
        assert!(inventories.len() >= 5, "{}", inventories.len());
        let problems = check(&inventories, &loaded, &floors(&suites).unwrap());
        assert!(problems.is_empty(), "{}", problems.join("\n"));
    }
}
