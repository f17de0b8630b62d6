//! EtherCAT end to end on raw Ethernet: `harness serve ecat` on one end of a veth pair, an
//! independent master (pysoem, SOEM's Python binding) inside a network namespace on the
//! other.
//!
//! Needs root (network namespaces, raw sockets) and the interop venv with pysoem
//! (`.ci/interop-setup`); without them the tests say so and skip on a developer's machine, and
//! fail in strict mode.

use std::path::PathBuf;
use std::time::Instant;

use harness::ecat_serve::{start, ServeOptions};
use serde_json::Value;

#[allow(dead_code)] // what the EtherNet/IP tests share
mod common;
use common::netns::{require_root_or_skip, Netns};
use common::peer::interop_python;

/// The interop venv's python with pysoem (`.ci/interop-setup`), or the test skips (fails in
/// strict mode).
fn python(why: &str) -> Option<PathBuf> {
    interop_python(&["pysoem"], why)
}

/// Runs `tests/interop/pysoem_master.py` on the namespace's end of the pair; one JSON object
/// per operation (and per emergency).
fn pysoem(ns: &Netns, py: &PathBuf, ops: &[&str]) -> Vec<Value> {
    let script =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/interop/pysoem_master.py");
    let t = Instant::now();
    let out = ns
        .command(py)
        .arg(script)
        .arg(ns.ns_if())
        .args(["--timeout", "2", "--deadline", "60"])
        .args(ops)
        .output()
        .expect("pysoem_master.py runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "pysoem_master.py {ops:?} ({:?}, {:?}): {stdout}\n{}",
        out.status,
        t.elapsed(),
        String::from_utf8_lossy(&out.stderr)
    );
    eprintln!("pysoem_master.py {ops:?} ({:?}):\n{stdout}", t.elapsed());
    stdout
        .lines()
        .filter(|l| l.starts_with('{'))
        .map(|l| serde_json::from_str::<Value>(l).expect("a JSON line"))
        .filter(|v| v["op"] != "emergency")
        .collect()
}

#[test]
fn pysoem_masters_the_served_slave_over_a_veth_pair() {
    let why = "pysoem (SOEM) against harness serve ecat";
    if !require_root_or_skip(why) {
        return;
    }
    let Some(py) = python(why) else { return };
    let ns = Netns::new("ecat");
    let served = start(&ServeOptions::new(ns.root_if())).expect("serve ecat");

    // Finds the slave: NORD's vendor id 538h (BU 0620 §2.2.7.1, object 1018h sub-index 1).
    // P102 of FI 3: 2000h + 1000h + 66h = 3066h, sub-index 1 (BU 0620 §2.2.7): read, write,
    // read back. Refusals: an object that does not exist (06020000h), a sub-index that does
    // not (06090011h), a write to a read-only object (CiA 301: 06010002h; BU 0620 §2.2.7.2
    // prints 06020002h, an erratum).
    let r = pysoem(
        &ns,
        &py,
        &[
            "scan", "read", "1018h", "1", "read", "3066h", "1", "write", "3066h", "1", "u16",
            "250", "read", "3066h", "1", "read", "1234h", "0", "read", "1018h", "9", "write",
            "1018h", "1", "u32", "5", "speed", "200", "1018h", "1",
        ],
    );
    assert_eq!(r.len(), 9, "{r:#?}");
    let slave = &r[0]["slaves"][0];
    assert_eq!(r[0]["slaves"].as_array().map(Vec::len), Some(1), "{}", r[0]);
    assert_eq!(slave["vendor"], 0x538, "{slave}");
    assert_eq!(r[1]["value"], 0x538, "{}", r[1]);
    assert_eq!(r[2]["ok"], true, "{}", r[2]);
    assert_eq!(r[3]["ok"], true, "{}", r[3]);
    assert_eq!(r[4]["value"], 250, "{}", r[4]);
    for (line, code) in [
        (&r[5], 0x0602_0000),
        (&r[6], 0x0609_0011),
        (&r[7], 0x0601_0002),
    ] {
        assert_eq!(line["ok"], false, "{line}");
        assert_eq!(line["abort_code"], code, "{line}");
    }
    // The speed mode (a figure for the bench, not judged here): 200 uploads, none refused.
    assert_eq!(
        (&r[8]["ok"], &r[8]["errors"]),
        (&true.into(), &0.into()),
        "{}",
        r[8]
    );

    // OP, then the switching example of the manual over process data (BU 0620 §5, inverter 1):
    // 047Eh -> status xx31h (ready to switch on), 047Fh with setpoint 2000h -> xx37h
    // (operation enabled).
    let r = pysoem(
        &ns,
        &py,
        &[
            "state", "op", "pdo", "047Eh", "0", "xx31h", "pdo", "047Fh", "2000h", "xx37h",
        ],
    );
    assert_eq!(r.len(), 3, "{r:#?}");
    assert_eq!(r[0]["ok"], true, "OP: {}", r[0]);
    assert_eq!(r[1]["ok"], true, "047Eh -> xx31h: {}", r[1]);
    assert_eq!(r[2]["ok"], true, "047Fh + 2000h -> xx37h: {}", r[2]);

    let stats = served
        .stop()
        .expect("the slave served without a link error");
    assert!(stats.frames > 100, "{stats:?}");
}

#[test]
fn netns_helpers_make_and_remove_a_namespace_with_a_veth_pair() {
    if !require_root_or_skip("network namespace helpers") {
        return;
    }
    let (name, root_if) = {
        let ns = Netns::new("selftest");
        ns.add_ipv4("10.231.0.1/30", "10.231.0.2/30");
        let out = ns.exec(&["ip", "-o", "addr", "show", "dev", ns.ns_if()]);
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(text.contains("10.231.0.2/30"), "{text}");
        // The inside end answers a ping from the root namespace over the pair (through the
        // pair's own end: another job's pair may carry the same subnet).
        let ping = std::process::Command::new("ping")
            .args(["-c", "1", "-W", "2", "-I", ns.root_if(), "10.231.0.2"])
            .output();
        if let Ok(p) = ping {
            assert!(p.status.success(), "{}", String::from_utf8_lossy(&p.stdout));
        }
        (ns.name().to_string(), ns.root_if().to_string())
    };
    assert!(!netns_exists(&name), "{name} left behind");
    assert!(!link_exists(&root_if), "{root_if} left behind");

    // A panic inside the test still removes everything.
    let made = std::sync::Mutex::new(None);
    let r = std::panic::catch_unwind(|| {
        let ns = Netns::new("panics");
        *made.lock().unwrap() = Some((ns.name().to_string(), ns.root_if().to_string()));
        panic!("on purpose");
    });
    assert!(r.is_err());
    let (name, root_if) = made.into_inner().unwrap().expect("made before the panic");
    assert!(!netns_exists(&name) && !link_exists(&root_if));
}

fn netns_exists(name: &str) -> bool {
    let out = std::process::Command::new("ip")
        .args(["netns", "list"])
        .output()
        .expect("ip runs");
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .any(|l| l.split_whitespace().next() == Some(name))
}

fn link_exists(name: &str) -> bool {
    std::process::Command::new("ip")
        .args(["link", "show", name])
        .stderr(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}
