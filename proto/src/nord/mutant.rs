//! Mutants of the manuals as code: one catalogued datum changed at a time, for `harness mutants`.
//!
//! A suite that passes whatever the device answers proves nothing. A mutation score measures
//! whether the cases notice a wrong datum: each mutant changes one value the manuals state (a
//! parameter's default, range, decimals, array size, writability or set dependence; an error
//! number; an abort code; an LED row; a status or control bit; an address formula's constant;
//! a time-out), and a mutant some case then fails on is killed.
//!
//! The tables and constants read their datum through this module: a [`Table`] derefs to its
//! rows, a [`Constant`] gives its value, a [`Bits`] hook sits where the inverter reads its
//! control word and writes its status word. A process that calls [`install`] before its first
//! look-up sees the one datum changed, everywhere: the simulator and the reference model alike.
//! Every other process, and every test, sees the manuals' values. The change is process-wide and
//! cannot be undone, by design: `harness mutants` runs each mutant in a child process of its own,
//! so nothing in-process can be disturbed by it.

use std::fmt;
use std::ops::Deref;
use std::sync::OnceLock;

use super::{addr, can, errors, led, params, pkw};

/// One datum changed: what `harness mutants` runs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Mutant {
    /// Stable within a build: `site/row/field`, e.g. `params/12/default`.
    pub id: String,
    /// What was changed, in the manuals' terms: "P102 default 200 → 201".
    pub what: String,
    /// Where the manuals state the datum: "BU 0620 §2.5.6.4 …".
    pub source: &'static str,
    /// The parameter the datum belongs to, if it is a parameter's: the cases that read or
    /// write it are the ones to notice.
    pub parameter: Option<u16>,
}

/// A mutant id that names no mutant of this build.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum InstallError {
    /// No site, row or field of that name.
    #[error("no mutant `{0}` (`harness mutants --list` lists them)")]
    Unknown(String),
    /// A mutant is installed already.
    #[error("mutant `{0}` is installed already: one per process")]
    Twice(String),
}

/// Installs the mutant `id` for the rest of the process. Call it before anything looks a datum
/// up: a table read earlier keeps the manuals' rows.
pub fn install(id: &str) -> Result<Mutant, InstallError> {
    let mutant = all()
        .into_iter()
        .find(|m| m.id == id)
        .ok_or_else(|| InstallError::Unknown(id.to_string()))?;
    let (site, rest) = id.split_once('/').unwrap_or((id, ""));
    let (row, field) = rest.split_once('/').unwrap_or((rest, ""));
    let target = Target {
        site: SITES
            .iter()
            .map(|s| s.name())
            .find(|n| *n == site)
            .ok_or_else(|| InstallError::Unknown(id.to_string()))?,
        row: row
            .parse()
            .map_err(|_| InstallError::Unknown(id.to_string()))?,
        field: field.to_string(),
    };
    INSTALLED
        .set(target)
        .map_err(|_| InstallError::Twice(id.to_string()))?;
    Ok(mutant)
}

/// Every mutant of this build, in site order.
pub fn all() -> Vec<Mutant> {
    SITES
        .iter()
        .flat_map(|site| {
            (0..site.rows()).flat_map(move |row| {
                site.changes(row)
                    .into_iter()
                    .map(move |(field, what)| Mutant {
                        id: format!("{}/{row}/{field}", site.name()),
                        what,
                        source: site.source(row),
                        parameter: site.parameter(row),
                    })
            })
        })
        .collect()
}

/// The datum installed in this process.
#[derive(Debug)]
struct Target {
    site: &'static str,
    row: usize,
    field: String,
}

static INSTALLED: OnceLock<Target> = OnceLock::new();

/// The field of `row` changed at `site` in this process, if any.
fn installed(site: &str, row: usize) -> Option<&'static str> {
    INSTALLED
        .get()
        .filter(|t| t.site == site && t.row == row)
        .map(|t| t.field.as_str())
}

/// Where data can be changed.
trait Site: Sync {
    fn name(&self) -> &'static str;
    fn rows(&self) -> usize;
    /// The row's changes: (field, description).
    fn changes(&self, row: usize) -> Vec<(&'static str, String)>;
    fn source(&self, row: usize) -> &'static str;
    fn parameter(&self, _row: usize) -> Option<u16> {
        None
    }
}

/// A row of a catalogued table: how it can be changed.
pub trait Row: Copy + Send + Sync + 'static {
    /// The changed rows, one per field: (field, description, row).
    fn changes(&self) -> Vec<(&'static str, String, Self)>;
    /// Where the manuals state this row, where it says so itself.
    fn source(&self) -> Option<&'static str> {
        None
    }
    /// The parameter the row describes, if it is one.
    fn parameter(&self) -> Option<u16> {
        None
    }
}

/// A table of the manuals, read through the installed mutant.
pub struct Table<T: 'static> {
    name: &'static str,
    source: &'static str,
    rows: &'static [T],
    seen: OnceLock<&'static [T]>,
}

impl<T: Row> Table<T> {
    /// The table `name` (an id part: lowercase, no `/`) of `rows`, stated in `source`.
    pub const fn new(name: &'static str, source: &'static str, rows: &'static [T]) -> Table<T> {
        Table {
            name,
            source,
            rows,
            seen: OnceLock::new(),
        }
    }
}

impl<T: Row> Deref for Table<T> {
    type Target = [T];

    fn deref(&self) -> &[T] {
        self.seen.get_or_init(|| {
            let changed = INSTALLED
                .get()
                .filter(|t| t.site == self.name)
                .and_then(|t| {
                    let row = self.rows.get(t.row)?.changes();
                    let (_, _, new) = row.into_iter().find(|(f, _, _)| *f == t.field)?;
                    Some((t.row, new))
                });
            match changed {
                Some((i, new)) => {
                    let mut rows = self.rows.to_vec();
                    rows[i] = new;
                    Vec::leak(rows)
                }
                None => self.rows,
            }
        })
    }
}

impl<T: Row> Site for Table<T> {
    fn name(&self) -> &'static str {
        self.name
    }
    fn rows(&self) -> usize {
        self.rows.len()
    }
    fn changes(&self, row: usize) -> Vec<(&'static str, String)> {
        self.rows[row]
            .changes()
            .into_iter()
            .map(|(f, what, _)| (f, what))
            .collect()
    }
    fn source(&self, row: usize) -> &'static str {
        self.rows[row].source().unwrap_or(self.source)
    }
    fn parameter(&self, row: usize) -> Option<u16> {
        self.rows[row].parameter()
    }
}

/// A number a constant can hold.
pub trait Value: Copy + fmt::Display + Send + Sync + 'static {
    /// The value one up (wrapping).
    fn plus_one(self) -> Self;
    /// The value one down (wrapping).
    fn minus_one(self) -> Self;
}

macro_rules! value {
    ($($t:ty),*) => {$(
        impl Value for $t {
            fn plus_one(self) -> Self {
                self.wrapping_add(1)
            }
            fn minus_one(self) -> Self {
                self.wrapping_sub(1)
            }
        }
    )*};
}
value!(u8, u16, u32);

/// A formula's constant or a time the manuals state; the mutant adds one, or, for a lower
/// bound ("≥ 5 ms"), takes one away: a value above a lower bound still keeps to it.
pub struct Constant<T: Value> {
    name: &'static str,
    value: T,
    what: &'static str,
    source: &'static str,
    lower_bound: bool,
}

impl<T: Value> Constant<T> {
    /// The constant `name` (an id part) of `value`, whose role `what` the mutant's description
    /// names, stated in `source`.
    pub const fn new(
        name: &'static str,
        value: T,
        what: &'static str,
        source: &'static str,
    ) -> Constant<T> {
        Constant {
            name,
            value,
            what,
            source,
            lower_bound: false,
        }
    }

    /// The constant is a lower bound the manuals state.
    pub const fn lower_bound(self) -> Constant<T> {
        Constant {
            lower_bound: true,
            ..self
        }
    }

    fn mutated(&self) -> T {
        match self.lower_bound {
            true => self.value.minus_one(),
            false => self.value.plus_one(),
        }
    }

    /// The value in this process.
    pub fn get(&self) -> T {
        match installed(self.name, 0) {
            Some(_) => self.mutated(),
            None => self.value,
        }
    }
}

impl<T: Value> Site for Constant<T> {
    fn name(&self) -> &'static str {
        self.name
    }
    fn rows(&self) -> usize {
        1
    }
    fn changes(&self, _: usize) -> Vec<(&'static str, String)> {
        vec![(
            if self.lower_bound {
                "minus-one"
            } else {
                "plus-one"
            },
            format!("{} {} → {}", self.what, self.value, self.mutated()),
        )]
    }
    fn source(&self, _: usize) -> &'static str {
        self.source
    }
}

/// The bits of a 16-bit word the inverter reads or writes; a mutant inverts one.
pub struct Bits {
    name: &'static str,
    what: &'static str,
    source: &'static str,
}

impl Bits {
    /// The word `what` ("status word"), whose bits `source` states.
    pub const fn new(name: &'static str, what: &'static str, source: &'static str) -> Bits {
        Bits { name, what, source }
    }

    /// The word as this process reads or writes it.
    pub fn apply(&self, word: u16) -> u16 {
        match INSTALLED.get().filter(|t| t.site == self.name) {
            Some(t) => word ^ (1 << t.row),
            None => word,
        }
    }
}

impl Site for Bits {
    fn name(&self) -> &'static str {
        self.name
    }
    fn rows(&self) -> usize {
        16
    }
    fn changes(&self, row: usize) -> Vec<(&'static str, String)> {
        vec![("inverted", format!("{} bit {row} inverted", self.what))]
    }
    fn source(&self, _: usize) -> &'static str {
        self.source
    }
}

/// Status word bits as the inverter writes them: every manual prints the table.
pub static STATUS_BITS: Bits = Bits::new(
    "status-bits",
    "status word",
    "BU 0620 §6.1.2.2 status word, BU 2100 §6.2.3, BU 2200 §6.3.2, BU 0590 §4.1.3",
);

/// Control word bits as the inverter reads them: every manual prints the table.
pub static CONTROL_BITS: Bits = Bits::new(
    "control-bits",
    "control word",
    "BU 0620 §6.1.2.1 control word, BU 2100 §6.2.2, BU 2200 §6.3.1, BU 0590 §4.1.2",
);

/// Every place a datum can be changed.
static SITES: &[&dyn Site] = &[
    &params::CATALOGUE,
    &errors::COMM_ERRORS,
    &errors::ETHERCAT_ABORTS,
    &errors::POWERLINK_ABORTS,
    &errors::POWERLINK_ERRORS,
    &errors::MODULE_ERRORS,
    &errors::POWERLINK_MODULE_E10,
    &errors::PROFINET_ALARM_BASE,
    &errors::LOST_INVERTER,
    &led::DEV,
    &led::BUS,
    &led::ETHERCAT_RUN,
    &led::ETHERCAT_ERR,
    &led::ETHERNETIP_MS,
    &led::ETHERNETIP_NS,
    &led::POWERLINK_BS,
    &led::POWERLINK_BE,
    &led::PROFINET_RUN,
    &led::TU3_PNT_ERR,
    &led::TU3_PNT_DS,
    &led::TU3_PNT_DE,
    &led::PROFINET_BF,
    &STATUS_BITS,
    &CONTROL_BITS,
    &addr::COE_INDEX,
    &addr::COE_DEVICE_STEP,
    &addr::CIP_CLASS_BASE,
    &addr::PNIO_RECORD_BASE,
    &pkw::PNU_OFFSET,
    &can::FIRST_INVERTER_ADDRESS,
    &can::ADDRESS_STEP,
    &can::ENCODER_OFFSET,
    &can::MIN_CYCLE_US,
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_are_unique_and_every_site_has_mutants() {
        let all = all();
        let ids: std::collections::BTreeSet<_> = all.iter().map(|m| m.id.as_str()).collect();
        assert_eq!(ids.len(), all.len(), "duplicate mutant ids");
        for site in SITES {
            assert!(
                all.iter()
                    .any(|m| m.id.starts_with(&format!("{}/", site.name()))),
                "{} has no mutant",
                site.name()
            );
        }
        assert!(all.len() > 500, "{} mutants", all.len());
    }

    #[test]
    fn every_mutant_names_a_manual() {
        for m in all() {
            assert!(
                m.source.starts_with("BU "),
                "{}: source {:?}",
                m.id,
                m.source
            );
        }
    }

    #[test]
    fn without_an_installed_mutant_the_data_are_the_manuals() {
        // No test installs a mutant: the hooks pass words through and constants keep their value.
        assert_eq!(STATUS_BITS.apply(0x0B31), 0x0B31);
        assert_eq!(addr::COE_INDEX.get(), 0x2000);
        assert!(std::ptr::eq(
            &*errors::COMM_ERRORS,
            errors::COMM_ERRORS.rows
        ));
    }

    #[test]
    fn an_unknown_id_is_refused_without_installing() {
        assert_eq!(
            install("params/99999/default"),
            Err(InstallError::Unknown("params/99999/default".into()))
        );
        assert!(INSTALLED.get().is_none());
    }
}
