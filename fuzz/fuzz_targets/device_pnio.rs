//! libFuzzer binary of the fuzz target `device_pnio` (`fuzz::targets::TARGETS`).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    (fuzz::targets::by_name("device_pnio").expect("a target").run)(data)
});
