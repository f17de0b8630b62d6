//! libFuzzer binary of the fuzz target `lldp` (`fuzz::targets::TARGETS`).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    (fuzz::targets::by_name("lldp").expect("a target").run)(data)
});
