//! What the fuzz targets (`fuzz/`, targets `suite` and `description`) need of the library:
//! the suite loader and the device-description readers on text from the fuzzer, through the
//! functions a run calls on the files it reads. Malformed text is a load error or a
//! description error, never a panic.

use std::collections::HashSet;
use std::path::Path;
use std::sync::OnceLock;

use crate::description::{text_of, Description};
use crate::suite::{inventory, Loaded, Vocabulary};

/// Loads `text` as a suite file with every bus's steps; returns how many cases loaded and how
/// many errors were reported.
pub fn suite(text: &str) -> (usize, usize) {
    static VOCABULARY: OnceLock<Vocabulary> = OnceLock::new();
    let vocabulary = VOCABULARY.get_or_init(|| crate::bus::vocabulary(crate::buses::BUSES));
    let mut loaded = Loaded::default();
    crate::suite::load_text(
        vocabulary,
        Path::new("fuzz.yaml"),
        "fuzz",
        text,
        &mut HashSet::new(),
        &mut loaded,
    );
    (loaded.cases.len(), loaded.errors.len())
}

/// Reads `text` as a statement inventory (`suites/inventory/`); whether it read.
pub fn inventory(text: &str) -> bool {
    inventory::parse_inventory(Path::new("fuzz.yaml"), text).is_ok()
}

/// Reads `bytes` as a device-description file (EDS, ESI, XDD or GSDML, told by content, as
/// `run --description` reads one); the identity it names, or the error.
pub fn description(bytes: &[u8]) -> Result<String, String> {
    Description::parse(&text_of(bytes.to_vec()), "fuzz")
        .map(|d| format!("{} {}", d.format(), d.identity()))
        .map_err(|e| e.to_string())
}
