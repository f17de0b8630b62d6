//! libFuzzer binary of the fuzz target `canopen` (`fuzz::targets::TARGETS`).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    (fuzz::targets::by_name("canopen").expect("a target").run)(data)
});
