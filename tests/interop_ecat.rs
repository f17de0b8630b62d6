//! EtherCAT end to end on raw Ethernet: `harness serve ecat` on one end of a veth pair, an
//! independent master (pysoem, SOEM's Python binding) inside a network namespace on the
//! other.
//!
//! Needs root (network namespaces, raw sockets) and the interop venv with pysoem
//! (`.ci/interop-setup`); without them the tests say so and skip on a developer's machine, and
//! fail when `CI` is set.

#[allow(dead_code)] // what the EtherNet/IP tests share
mod common;
use common::netns::{require_root_or_skip, Netns};

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
        // The inside end answers a ping from the root namespace over the pair.
        let ping = std::process::Command::new("ping")
            .args(["-c", "1", "-W", "2", "10.231.0.2"])
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
