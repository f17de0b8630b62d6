//! Where the suites are when `--suites` is not given: `./suites`, else the suites of the
//! checkout the harness was built in, said on stderr.

use std::path::{Path, PathBuf};

/// The suites folder: as given, else `suites/` of the current directory, else the one of the
/// checkout the harness was built in, with a note on stderr saying so (a binary run from
/// elsewhere would otherwise test suites the user never chose, silently). When there is none,
/// `suites`, for the caller's load error to name.
pub(crate) fn suites_dir(given: Option<PathBuf>) -> PathBuf {
    suites_or_usage(given).unwrap_or_else(|e| {
        eprintln!("harness: {e}");
        PathBuf::from("suites")
    })
}

/// The suites folder or why there is none: as given; else `here` (`./suites`); else `built`
/// (the build checkout's), with the note to print.
pub(super) fn default_suites(
    given: Option<PathBuf>,
    here: &Path,
    built: &Path,
) -> Result<(PathBuf, Option<String>), String> {
    if let Some(dir) = given {
        return Ok((dir, None));
    }
    if here.is_dir() {
        return Ok((here.to_path_buf(), None));
    }
    let cwd = std::env::current_dir()
        .map(|d| d.display().to_string())
        .unwrap_or_else(|_| ".".into());
    if built.is_dir() {
        let built = built.canonicalize().unwrap_or_else(|_| built.to_path_buf());
        return Ok((
            built.clone(),
            Some(format!(
                "no `suites/` in {cwd}: using the suites of the checkout this harness was built in, {} (`--suites DIR` chooses)",
                built.display()
            )),
        ));
    }
    Err(format!(
        "no suites: no `suites/` in {cwd}, and the checkout this harness was built in ({}) has none; give `--suites DIR`",
        built.display()
    ))
}

/// The suites folder for `run` and `list`: [`default_suites`], the note printed; none is a
/// usage error.
pub(crate) fn suites_or_usage(given: Option<PathBuf>) -> Result<PathBuf, String> {
    let built = Path::new(env!("CARGO_MANIFEST_DIR")).join("../suites");
    let (dir, note) = default_suites(given, Path::new("suites"), &built)?;
    if let Some(n) = note {
        eprintln!("harness: {n}");
    }
    Ok(dir)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_suites_are_the_given_then_here_then_the_build_checkouts_with_a_note() {
        let dir = std::env::temp_dir().join(format!("suites-default-{}", std::process::id()));
        let (here, built) = (dir.join("here"), dir.join("built"));
        let given = Some(PathBuf::from("mine"));
        // Neither folder exists: a usage error naming both ways out.
        assert_eq!(
            default_suites(given.clone(), &here, &built),
            Ok((PathBuf::from("mine"), None))
        );
        let e = default_suites(None, &here, &built).unwrap_err();
        assert!(
            e.contains("--suites DIR") && e.contains(&built.display().to_string()),
            "{e}"
        );
        std::fs::create_dir_all(&built).unwrap();
        let (got, note) = default_suites(None, &here, &built).unwrap();
        assert_eq!(got, built.canonicalize().unwrap());
        let note = note.expect("a note when the build checkout's suites are used");
        assert!(
            note.contains("checkout this harness was built in"),
            "{note}"
        );
        std::fs::create_dir_all(&here).unwrap();
        assert_eq!(
            default_suites(None, &here, &built),
            Ok((here.clone(), None))
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
