//! libFuzzer binary of the fuzz target `nord` (`fuzz::targets::TARGETS`).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    (fuzz::targets::by_name("nord").expect("a target").run)(data)
});
