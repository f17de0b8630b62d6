//! libFuzzer binary of the fuzz target `pnio_rpc` (`fuzz::targets::TARGETS`).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    (fuzz::targets::by_name("pnio_rpc").expect("a target").run)(data)
});
