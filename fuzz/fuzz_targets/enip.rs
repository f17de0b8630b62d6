//! libFuzzer binary of the fuzz target `enip` (`fuzz::targets::TARGETS`).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    (fuzz::targets::by_name("enip").expect("a target").run)(data)
});
