//! What the end-to-end tests share: the simulator served by the `harness` binary.

use std::io::{BufRead, BufReader};
use std::net::{SocketAddr, TcpStream};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

pub(crate) mod addr;
pub(crate) mod cli;
pub(crate) mod ecat_wire;
pub(crate) mod hog;
pub(crate) mod netns;
pub(crate) mod peer;
pub(crate) mod pnio_wire;
pub(crate) mod suite_run;
pub(crate) mod transcripts;
pub(crate) mod tshark;

/// A child process, killed when dropped (a served simulator, a third-party server).
pub(crate) struct Server(pub(crate) Child);

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// `harness serve enip --listen LISTEN --profile PROFILE`, bounded to `seconds` should the
/// test die without killing it; returns once it accepts TCP connections. LISTEN is an address
/// of the test's own ([`addr::free_loopback`]), never a fixed one another job may hold.
pub(crate) fn serve(listen: &str, profile: &str, seconds: u32) -> Server {
    serve_with(listen, profile, seconds, &[])
}

/// [`serve`] with further `harness serve enip` arguments.
pub(crate) fn serve_with(listen: &str, profile: &str, seconds: u32, extra: &[&str]) -> Server {
    let mut child = Command::new(env!("CARGO_BIN_EXE_harness"))
        .args(["serve", "enip", "--listen", listen, "--profile", profile])
        .args(["--seconds", &seconds.to_string()])
        .args(extra)
        .stdout(Stdio::piped())
        .spawn()
        .expect("harness serve starts");
    // It announces itself once its sockets are bound, and exits at once when it cannot bind
    // them: then whatever holds the address would answer in its place.
    let mut out = BufReader::new(child.stdout.take().expect("piped stdout"));
    let mut line = String::new();
    if out.read_line(&mut line).unwrap_or(0) == 0 {
        let status = child.wait();
        panic!("harness serve --listen {listen} did not start ({status:?}): address taken?");
    }
    print!("{line}");
    std::thread::spawn(move || std::io::copy(&mut out, &mut std::io::stdout()));
    wait_listening(listen, Duration::from_secs(10));
    Server(child)
}

/// Returns once `listen` (HOST:PORT) accepts TCP connections; panics after `within`.
pub(crate) fn wait_listening(listen: &str, within: Duration) {
    let addr: SocketAddr = listen.parse().expect("listen is HOST:PORT");
    let deadline = Instant::now() + within;
    while TcpStream::connect_timeout(&addr, Duration::from_millis(200)).is_err() {
        assert!(Instant::now() < deadline, "nothing listens on {listen}");
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// The verdict and message of case `id` in a `run.json` (the first case-run of that id).
pub(crate) fn case_verdict<'a>(run: &'a serde_json::Value, id: &str) -> (&'a str, &'a str) {
    let c = run["cases"]
        .as_array()
        .expect("run.json lists cases")
        .iter()
        .find(|c| c["id"] == id)
        .unwrap_or_else(|| panic!("no case {id}"));
    (
        c["verdict"].as_str().unwrap_or_default(),
        c["message"].as_str().unwrap_or_default(),
    )
}

/// `harness run` (made by `harness`, in a namespace or not) of the cases whose id contains
/// `filter` for `profile` against `dut`: the report's cases (the connection check's, when the
/// run stopped there).
pub(crate) fn cases_of_run(
    harness: Command,
    profile: &str,
    dut: &str,
    filter: &str,
) -> Vec<serde_json::Value> {
    static RUNS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let mut harness = harness;
    let n = RUNS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("harness-run-{}-{n}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let suites = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../suites");
    let run = harness
        .args(["run", "--profile", profile, "--suites"])
        .arg(&suites)
        .args(["--filter", filter, "--dut", dut, "--allow-motion", "--out"])
        .arg(&dir)
        .output()
        .expect("harness run starts");
    let report: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("run.json"))
            .unwrap_or_else(|e| panic!("run.json: {e}: {}", String::from_utf8_lossy(&run.stderr))),
    )
    .unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&run.stdout)));
    let _ = std::fs::remove_dir_all(&dir);
    report["cases"].as_array().expect("cases").clone()
}

/// `harness serve BUS --iface IFACE --profile PROFILE EXTRA… --system-bus RELAY` for three
/// minutes at most, once the relay (socketcand, the served device's gateway frames) listens.
pub(crate) fn serve_on_iface_with_relay(
    bus: &str,
    iface: &str,
    profile: &str,
    extra: &[&str],
    relay: &str,
) -> Server {
    let child = Command::new(env!("CARGO_BIN_EXE_harness"))
        .args(["serve", bus, "--iface", iface, "--profile", profile])
        .args(extra)
        .args(["--system-bus", relay, "--seconds", "180"])
        .stdout(Stdio::null())
        .spawn()
        .unwrap_or_else(|e| panic!("harness serve {bus} starts: {e}"));
    let server = Server(child);
    wait_listening(relay, Duration::from_secs(10));
    server
}

/// Both sides of a served device's gateway: `harness` (made by `harness`, in a namespace or
/// not) runs the cases whose id contains `filter` with `args` (profile and DUT), once with
/// `--tap socketcand://BUS/can0` and once without. With the tap every case of `ids` passes;
/// without it the first is not applicable, saying it needs `system-bus`.
pub(crate) fn check_tap_runs(
    harness: impl Fn() -> Command,
    args: &[&str],
    filter: &str,
    bus: &str,
    ids: &[&str],
) {
    let out_dir = std::env::temp_dir().join(format!(
        "nord-tap-{}-{}",
        std::process::id(),
        filter.replace('/', "-")
    ));
    let run = |tap: bool| {
        let mut c = harness();
        c.args(["run", "--allow-motion", "--filter", filter])
            .args(args)
            .arg("--out")
            .arg(&out_dir);
        if tap {
            c.args(["--tap", &format!("socketcand://{bus}/can0")]);
        }
        let out = c.output().expect("harness runs");
        let report: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out_dir.join("run.json")).unwrap()).unwrap();
        (out, report)
    };
    let (out, report) = run(true);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}");
    for id in ids {
        assert_eq!(case_verdict(&report, id).0, "pass", "{id}: {stdout}");
    }
    let (_, report) = run(false);
    let (verdict, message) = case_verdict(&report, ids[0]);
    assert_eq!(verdict, "not_applicable");
    assert!(message.contains("needs `system-bus`"), "{message}");
    let _ = std::fs::remove_dir_all(&out_dir);
}

/// `harness serve can --socketcand LISTEN --profile sk550p EXTRA…` for two minutes at most,
/// once it listens: the SK 550P's simulated system bus for the tests that reach it over
/// socketcand.
pub(crate) fn serve_can(listen: &str, extra: &[&str]) -> Server {
    let child = Command::new(env!("CARGO_BIN_EXE_harness"))
        .args([
            "serve",
            "can",
            "--socketcand",
            listen,
            "--profile",
            "sk550p",
        ])
        .args(["--seconds", "120"])
        .args(extra)
        .stdout(Stdio::null())
        .spawn()
        .expect("harness serve can starts");
    let server = Server(child);
    wait_listening(listen, Duration::from_secs(10));
    server
}
