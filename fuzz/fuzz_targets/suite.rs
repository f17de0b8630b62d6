//! libFuzzer binary of the fuzz target `suite` (`fuzz::targets::TARGETS`).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    (fuzz::targets::by_name("suite").expect("a target").run)(data)
});
