//! The text targets: the harness's suite loader and device-description readers
//! (`harness::fuzz_support`) on the fuzzer's bytes.

/// A suite file and a statement inventory: YAML as `harness run` loads it (files that are not
/// UTF-8 do not load, as `read_to_string` refuses them).
pub fn suite(data: &[u8]) {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = harness::fuzz_support::suite(text);
        let _ = harness::fuzz_support::inventory(text);
    }
}

/// A device description (EDS, ESI, XDD, GSDML), as `run --description FILE` reads one.
pub fn description(data: &[u8]) {
    let _ = harness::fuzz_support::description(data);
}
