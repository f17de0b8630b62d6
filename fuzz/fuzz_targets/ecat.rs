//! libFuzzer binary of the fuzz target `ecat` (`fuzz::targets::TARGETS`).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    (fuzz::targets::by_name("ecat").expect("a target").run)(data)
});
