//! Coverage-guided fuzzing of the project (issue 24): every codec of `proto`, every simulated
//! device of `sim` driven as a session with time passing, and the harness's suite loader and
//! device-description readers.
//!
//! Each target is a plain function of the fuzzer's bytes ([`targets::all`]); a crash is a
//! panic (overflow included: the instrumented build has debug assertions), an allocation past
//! the fuzzer's limit, a hang past its timeout, or a device that no longer answers a good
//! request after the session ([`devices`]). The libFuzzer binaries (`fuzz_targets/`, feature
//! `libfuzzer`) call these functions; so does the corpus replay (`tests/corpus.rs`), which
//! runs every file of `corpus/<target>/` through its target on stable Rust in `cargo test`.
//! `docs/fuzzing.md` says how to run a campaign and what the last one found.

pub mod devices;
pub mod parsers;
pub mod session;
pub mod targets;
#[cfg(feature = "texts")]
pub mod texts;
