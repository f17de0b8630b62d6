//! libFuzzer binary of the fuzz target `can` (`fuzz::targets::TARGETS`).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    (fuzz::targets::by_name("can").expect("a target").run)(data)
});
