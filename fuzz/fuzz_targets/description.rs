//! libFuzzer binary of the fuzz target `description` (`fuzz::targets::TARGETS`).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    (fuzz::targets::by_name("description").expect("a target").run)(data)
});
