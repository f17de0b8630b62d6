//! libFuzzer binary of the fuzz target `epl` (`fuzz::targets::TARGETS`).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    (fuzz::targets::by_name("epl").expect("a target").run)(data)
});
