//! The corpus replayed on stable Rust: every file of `fuzz/corpus/<target>/` (and of
//! `fuzz/regressions/<target>/`, the inputs that once crashed) through its target's function,
//! as the libFuzzer binary runs it. Cheap (no instrumented build), so `cargo test` catches a
//! change that makes a stored input crash without running the fuzzer.

use std::path::Path;

use fuzz::targets;

#[test]
fn every_corpus_file_runs_through_its_target() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut count = 0;
    for target in targets::all() {
        for folder in ["corpus", "regressions"] {
            let dir = root.join(folder).join(target.name);
            let Ok(entries) = std::fs::read_dir(&dir) else {
                assert!(folder != "corpus", "{} has no corpus", target.name);
                continue;
            };
            for entry in entries {
                let path = entry.expect("a corpus entry").path();
                let bytes = std::fs::read(&path).expect("a corpus file");
                let run = std::panic::catch_unwind(|| (target.run)(&bytes));
                assert!(run.is_ok(), "{} crashes on {}", target.name, path.display());
                count += 1;
            }
        }
    }
    assert!(count >= targets::all().count(), "only {count} corpus files");
}
