//! The run the raw-Ethernet network tests (EtherCAT, POWERLINK, PROFINET IO) share: in a
//! scratch folder, `harness run --profile P --dut URL` from inside the namespace with its own
//! `--pcap`, while tshark captures the wire there; the run must end with no case failed or in
//! error. What each bus then checks of the captures stays in its own test, or in a module of
//! its own when the load test makes the same run (`ecat_wire`, `pnio_wire`).

use std::collections::BTreeMap;
use std::path::PathBuf;

use serde_json::Value;

use super::netns::Netns;
use super::tshark::Capture;

/// A finished run of every suite for one profile against a served device.
pub(crate) struct SuiteRun {
    dir: PathBuf,
    /// The run's own capture (`--pcap`): each frame labelled with its case and step.
    pub(crate) run_pcap: PathBuf,
    /// tshark's capture of the namespace's interface meanwhile.
    pub(crate) wire_pcap: PathBuf,
    /// What the run printed.
    pub(crate) stdout: String,
    cases: Vec<Value>,
    label: String,
}

impl SuiteRun {
    /// Runs the suites for `profile` against `dut` from inside `ns` and checks the run: no case
    /// failed or in error, exit 0. The served simulator must be up; `tag` names the scratch
    /// folder.
    pub(crate) fn new(ns: &Netns, tag: &str, profile: &str, dut: &str) -> SuiteRun {
        SuiteRun::with_args(ns, tag, profile, dut, &[])
    }

    /// [`SuiteRun::new`] with the cases in the order of `--shuffle seed`.
    pub(crate) fn shuffled(ns: &Netns, tag: &str, profile: &str, dut: &str, seed: u64) -> SuiteRun {
        SuiteRun::with_args(ns, tag, profile, dut, &["--shuffle", &seed.to_string()])
    }

    fn with_args(ns: &Netns, tag: &str, profile: &str, dut: &str, extra: &[&str]) -> SuiteRun {
        let dir = std::env::temp_dir().join(format!(
            "harness-network-{tag}-{}-{profile}",
            std::process::id()
        ));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let (out, run_pcap, wire_pcap) = (
            dir.join("out"),
            dir.join("run.pcapng"),
            dir.join("wire.pcapng"),
        );
        let suites = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../suites");
        let capture = Capture::start(ns, ns.ns_if(), &wire_pcap);
        let run = ns
            .command(env!("CARGO_BIN_EXE_harness"))
            .args(["run", "--profile", profile, "--suites"])
            .arg(&suites)
            .args(["--dut", dut])
            // The served simulator has no motor to turn and no EEPROM to wear.
            .args(["--allow-motion", "--max-eeprom-writes", "10000"])
            .arg("--out")
            .arg(&out)
            .arg("--pcap")
            .arg(&run_pcap)
            .args(extra)
            .output()
            .expect("harness run starts");
        capture.stop();
        let stdout = String::from_utf8_lossy(&run.stdout).into_owned();
        let report: Value = serde_json::from_str(
            &std::fs::read_to_string(out.join("run.json")).expect("run.json written"),
        )
        .unwrap();
        let cases = report["cases"].as_array().expect("cases").clone();
        let bad: Vec<String> = cases
            .iter()
            .filter(|c| c["verdict"] == "fail" || c["verdict"] == "error")
            .map(|c| format!("{} {}: {}", c["id"], c["verdict"], c["message"]))
            .collect();
        assert!(bad.is_empty(), "{profile}: {}\n{stdout}", bad.join("\n"));
        assert_eq!(run.status.code(), Some(0), "{profile}: {stdout}");
        SuiteRun {
            dir,
            run_pcap,
            wire_pcap,
            stdout,
            cases,
            label: profile.to_string(),
        }
    }

    /// Asserts that at least so many cases passed whose ids start with each prefix.
    pub(crate) fn assert_passed<P: AsRef<str>>(&self, at_least: &[(P, usize)]) {
        for (prefix, n) in at_least {
            let prefix = prefix.as_ref();
            let passed = self
                .cases
                .iter()
                .filter(|c| c["verdict"] == "pass")
                .filter(|c| c["id"].as_str().is_some_and(|id| id.starts_with(prefix)))
                .count();
            assert!(
                passed >= *n,
                "{} {prefix}: {passed} cases passed, {n} expected\n{}",
                self.label,
                self.stdout
            );
        }
    }

    /// Each case's verdict and message, by id.
    pub(crate) fn verdicts(&self) -> BTreeMap<String, (String, String)> {
        self.cases
            .iter()
            .map(|c| {
                let s = |k: &str| c[k].as_str().unwrap_or_default().to_string();
                (s("id"), (s("verdict"), s("message")))
            })
            .collect()
    }

    /// Removes the scratch folder; a failing test keeps it to look at.
    pub(crate) fn finish(self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}
