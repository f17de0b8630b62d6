//! What the speed benches share (each bench target includes this file as its `common`
//! module): the interop venv's Python and its bench scripts, clients run concurrently, the
//! wording of a target met, the served device (`served`: the bench driver's `harness serve
//! BUS`), the minimal EtherNet/IP client (`enip_client`), and the second network namespace the
//! raw-Ethernet benches put their clients in (so that neither end of their veth pair has an
//! address in the root namespace, where a test running meanwhile may use the same subnet). The figures themselves
//! are in `harness::stats`.

// Each bench uses part of this.
#![allow(dead_code)]

use std::fs::File;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Barrier;
use std::thread;
use std::time::{Duration, Instant};

use harness::stats::Rate;

pub(crate) mod enip_client;
pub(crate) mod served;

/// `met` or `NOT met`: a bench prints whether a target was met, it does not fail.
pub(crate) fn met(ok: bool) -> &'static str {
    if ok {
        "met"
    } else {
        "NOT met"
    }
}

/// The interop venv's Python (`$INTEROP_VENV/bin/python`, else that of the venv
/// `.ci/interop-setup` makes in the build folder, `<target dir>/interop-venv`), when it exists.
pub(crate) fn interop_python() -> Option<PathBuf> {
    let venv = std::env::var_os("INTEROP_VENV")
        .filter(|v| !v.is_empty())
        .map_or_else(
            // Cargo's scratch folder for benches is `<target dir>/tmp`.
            || Path::new(env!("CARGO_TARGET_TMPDIR")).with_file_name("interop-venv"),
            PathBuf::from,
        );
    let python = Path::new(&venv).join("bin/python");
    python.exists().then_some(python)
}

/// What a Python bench script did.
pub(crate) enum Script {
    /// It could not run here: no venv, or its library not importable (exit code 3).
    Skipped(String),
    /// It ran and failed, overran its time, or said nothing readable.
    Failed(String),
    /// Its last JSON line, without an `error` member.
    Ran(serde_json::Value),
}

/// Runs `script ARGS` with the interop venv's `python`, waiting up to `limit` (plus start-up
/// time); the script prints one JSON line at the end (`{"error": …}` when it failed) and exits
/// with 3 when `library` cannot be imported.
pub(crate) fn run_script(
    python: Option<&Path>,
    script: &Path,
    args: &[String],
    library: &str,
    limit: Duration,
) -> Script {
    let name = script
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| script.display().to_string());
    let Some(python) = python else {
        return Script::Skipped(
            "no interop venv at ${INTEROP_VENV:-target/interop-venv}; run `bash .ci/interop-setup`"
                .into(),
        );
    };
    let child = Command::new(python)
        .arg(script)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn();
    let mut child = match child {
        Ok(c) => c,
        Err(e) => return Script::Failed(format!("cannot run {}: {e}", python.display())),
    };
    // Python's start and the library's import on top of the measured time.
    let deadline = Instant::now() + limit + Duration::from_secs(30);
    loop {
        match child.try_wait() {
            Ok(Some(_)) => break,
            Ok(None) if Instant::now() < deadline => thread::sleep(Duration::from_millis(20)),
            Ok(None) => {
                let _ = child.kill();
                let _ = child.wait();
                return Script::Failed(format!("{name} overran its time limit"));
            }
            Err(e) => return Script::Failed(e.to_string()),
        }
    }
    let out = match child.wait_with_output() {
        Ok(o) => o,
        Err(e) => return Script::Failed(e.to_string()),
    };
    let stderr = String::from_utf8_lossy(&out.stderr).trim().to_string();
    match out.status.code() {
        Some(0) => {}
        Some(3) => return Script::Skipped(format!("{library} not importable: {stderr}")),
        _ => return Script::Failed(format!("{name} {}: {stderr}", out.status)),
    }
    let stdout = String::from_utf8_lossy(&out.stdout);
    let Some(v) = stdout
        .lines()
        .rev()
        .find_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
    else {
        return Script::Failed(format!("no JSON line from {name}: {stdout}"));
    };
    match v.get("error").and_then(serde_json::Value::as_str) {
        Some(e) => Script::Failed(e.to_string()),
        None => Script::Ran(v),
    }
}

/// Aggregate rate of `clients` threads, each with its own client from `connect` (made in the
/// thread: a scanner stays on the thread that made it), all started together, each doing
/// `one` up to `per_client` times within `limit`. The first error of any thread is returned.
pub(crate) fn concurrent<C>(
    clients: usize,
    per_client: u32,
    limit: Duration,
    connect: impl Fn() -> Result<C, String> + Sync,
    one: impl Fn(&mut C) -> Result<(), String> + Sync,
) -> Result<Rate, String> {
    let go = Barrier::new(clients + 1);
    thread::scope(|scope| {
        let threads: Vec<_> = (0..clients)
            .map(|_| {
                scope.spawn(|| -> Result<(u64, Instant), String> {
                    let client = connect();
                    // Every thread reaches the barrier, even one that could not connect.
                    go.wait();
                    let mut client = client?;
                    let start = Instant::now();
                    let mut n = 0u64;
                    while n < u64::from(per_client) && start.elapsed() < limit {
                        one(&mut client)?;
                        n += 1;
                    }
                    // Ended before the client is dropped (its session closed).
                    Ok((n, Instant::now()))
                })
            })
            .collect();
        go.wait();
        let start = Instant::now();
        let mut count = 0;
        let mut end = start;
        let mut error = None;
        for t in threads {
            match t.join() {
                Ok(Ok((n, at))) => {
                    count += n;
                    end = end.max(at);
                }
                Ok(Err(e)) => {
                    error.get_or_insert(e);
                }
                Err(_) => {
                    error.get_or_insert("a client thread panicked".into());
                }
            }
        }
        match error {
            Some(e) => Err(e),
            None => Ok(Rate {
                count,
                secs: (end - start).as_secs_f64(),
            }),
        }
    })
}

/// Runs `ip ARGS…`; its error message when it fails.
pub(crate) fn ip(args: &[&str]) -> Result<(), String> {
    let out = Command::new("ip")
        .args(args)
        .output()
        .map_err(|e| format!("cannot run ip: {e}"))?;
    if out.status.success() {
        Ok(())
    } else {
        Err(format!(
            "ip {}: {}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr).trim()
        ))
    }
}

/// The clients' namespace: the root-side end of a `tests/common/netns.rs` pair moved into a
/// namespace of its own (named as `netns.rs` names them, so one left by a killed run is
/// cleaned up by the next) with `addr` on it, deleted when dropped.
pub(crate) struct ClientNs {
    pub(crate) name: String,
    pub(crate) iface: String,
}

impl ClientNs {
    /// Moves `root_if` into a new namespace named after `tag` and gives it `addr` (`A.B.C.D/N`).
    pub(crate) fn new(root_if: &str, tag: &str, addr: &str) -> Result<ClientNs, String> {
        let name = format!("nord-test-{}-99-{tag}", std::process::id());
        ip(&["netns", "add", &name])?;
        let ns = ClientNs {
            name,
            iface: root_if.to_string(),
        };
        ip(&["link", "set", "dev", &ns.iface, "netns", &ns.name])?;
        ip(&["-n", &ns.name, "link", "set", "lo", "up"])?;
        // Moved, the end has its new namespace's defaults: IPv6 off again (no router
        // solicitations or MLD reports on the wire).
        let _ = Command::new("ip")
            .args(["netns", "exec", &ns.name, "sh", "-c"])
            .arg(format!(
                "echo 1 > /proc/sys/net/ipv6/conf/{}/disable_ipv6",
                ns.iface
            ))
            .stderr(Stdio::null())
            .status();
        ip(&["-n", &ns.name, "addr", "add", addr, "dev", &ns.iface])?;
        ip(&["-n", &ns.name, "link", "set", &ns.iface, "up"])?;
        Ok(ns)
    }

    /// Runs `f` in a thread of this namespace ([`in_netns`]).
    pub(crate) fn run<T: Send>(&self, f: impl FnOnce() -> T + Send) -> Result<T, String> {
        in_netns(&self.name, f)
    }
}

impl Drop for ClientNs {
    fn drop(&mut self) {
        let _ = Command::new("ip")
            .args(["netns", "del", &self.name])
            .stderr(Stdio::null())
            .status();
    }
}

/// Waits (5 s at most) until `ip -n NS link show dev IFACE` says the link is up with its
/// queueing discipline attached.
pub(crate) fn wait_carrier(ns: &str, iface: &str) -> Result<(), String> {
    let start = Instant::now();
    loop {
        let out = Command::new("ip")
            .args(["-n", ns, "-o", "link", "show", "dev", iface])
            .output()
            .map_err(|e| format!("cannot run ip: {e}"))?;
        let text = String::from_utf8_lossy(&out.stdout);
        if text.contains("state UP") && !text.contains("qdisc noop") {
            return Ok(());
        }
        if start.elapsed() > Duration::from_secs(5) {
            return Err(format!("{iface} does not come up in {ns}: {text}"));
        }
        thread::sleep(Duration::from_millis(5));
    }
}

/// Runs `f` in a thread of its own inside the network namespace `ns` (`/run/netns/NS`): the
/// sockets it opens and the processes it starts are that namespace's.
pub(crate) fn in_netns<T: Send>(ns: &str, f: impl FnOnce() -> T + Send) -> Result<T, String> {
    use nix::sched::{setns, CloneFlags};
    thread::scope(|scope| {
        scope
            .spawn(|| {
                let fd = File::open(format!("/run/netns/{ns}"))
                    .map_err(|e| format!("network namespace {ns}: {e}"))?;
                setns(&fd, CloneFlags::CLONE_NEWNET)
                    .map_err(|e| format!("setns into {ns}: {e}"))?;
                Ok(f())
            })
            .join()
            .unwrap_or_else(|_| Err(format!("the thread in {ns} panicked")))
    })
}
