//! PROFINET IO end to end with independent third-party peers: the harness's simulated device
//! (`harness::pnio_serve`, as `harness serve pnio` serves it) on the root end of a veth pair,
//! the peers inside a network namespace on the other end, for both PROFINET products (SK 550P,
//! SK TU3-PNT):
//!
//! - pnio-dcp (PyPI, driven by `tests/interop/pnio_dcp_peer.py`): DCP Identify (all and
//!   unicast), Get NameOfStation / IP, Set NameOfStation and Set IP; the Identify that follows
//!   shows what was set. scapy's DCP layers then find the device by its new name, not its old.
//! - scapy's PROFINET layers (`tests/interop/scapy_pnio_peer.py`): Identify parsed by scapy,
//!   Connect (ARBlockReq, IOCRs, AlarmCR, ExpectedSubmodules), PrmEnd, the device's own
//!   ApplicationReady call answered (after which its input frames say "run"), data record 101
//!   with the P102 example of BU 0620 §2.5.6.4, the refusals of a wrong slot, index and length,
//!   Release, and a read in the released AR. On the SK 550P, a timed run of record reads: the
//!   reads per second are printed, not judged.
//!
//! The device has `192.168.47.200/24` (pnio-dcp) or `192.168.48.200/24` (scapy), the peers
//! `.1` inside the namespace: not the SK 550P's factory subnet 192.168.20.0/24, which other
//! PROFINET tests may serve on in the root namespace at the same time.
//!
//! Needs root (network namespaces, raw sockets) and the interop venv with pnio_dcp and scapy
//! (`.ci/interop-setup`); without them the tests say so and skip on a developer's machine, and
//! fail in strict mode.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::{Duration, Instant};

use harness::pnio_serve::{start, ServeOptions, Served};
use proto::nord::pnio::{device_id, station_type};
use proto::nord::Product;
use serde_json::Value;

#[allow(dead_code)] // what the other network tests share
mod common;
use common::netns::{require_root_or_skip, Netns};
use common::peer::interop_python;

/// NORD's vendor id as the device reports it over DCP (`proto::nord::pnio::VENDOR_ID`).
const VENDOR_ID: u64 = 0x0538;
/// The name of station the device is served with.
const NAME: &str = "nord-device";
/// The name pnio-dcp gives it.
const RENAMED: &str = "nord-renamed";
/// BU 0620 §2.5.6.4: P102 [-02] = 2.5 s (PWE 250) through record 101, "24 4E 01 00 00 00 00
/// FA" ...
const P102_ORDER: &str = "244E0100000000FA";
/// ... and its answer after "Read Response (−)": response label 1, P102 + 1000, IND 1, 250.
const P102_ANSWER: &str = "144e0100000000fa";
/// "Read Response (−)" (DE 80 B5 00: IODReadRes, PNIORW, state conflict): the order is not
/// processed yet, or no order is pending.
const BUSY: &str = "DE80B500";

/// A PROFINET product as the peers see it.
struct Target {
    profile: &'static str,
    product: Product,
    /// The product's MAC address: SK 550P F0:5F:5A… (BU 0620 §4.4.3 P878), SK TU3-PNT the
    /// example of BU 0590 §5.1.4 P181.
    mac: &'static str,
    /// The expected submodules (`SLOT,SUBSLOT,MODULE_IDENT,SUBMODULE_IDENT,IN,OUT`): the DAP
    /// with interface and ports, and PPO 4 (4 words each way) for FI 1 in slot 3, whose ident
    /// is the value the PPO-type parameter shows (SK 550P P879 7, BU 0620 §4.4.3; SK TU3-PNT
    /// P180 4, BU 0590 §5.1.4); the SK TU3-PNT's DIG-IO module (P180 2) in slot 2.
    layout: &'static [&'static str],
}

const DAP: [&str; 4] = [
    "0,1,1,1,0,0",
    "0,0x8000,1,0x8000,0,0",
    "0,0x8001,1,0x8001,0,0",
    "0,0x8002,1,0x8002,0,0",
];

const TARGETS: [Target; 2] = [
    Target {
        profile: "sk550p",
        product: Product::Sk550p,
        mac: "f0:5f:5a:00:05:50",
        layout: &[DAP[0], DAP[1], DAP[2], DAP[3], "3,1,7,7,8,8"],
    },
    Target {
        profile: "tu3-pnt",
        product: Product::Tu3Pnt,
        mac: "00:0e:cf:03:60:00",
        layout: &[DAP[0], DAP[1], DAP[2], DAP[3], "2,1,2,2,2,2", "3,1,4,4,8,8"],
    },
];

/// FI 1's slot on both products (BU 0620 §2.5.6.2 "FI 1 (Slot 3)", BU 0590 §4.2.1).
const FI1_SLOT: &str = "3";

/// The device served on the root end of a fresh veth pair; dropped in field order: the device
/// stops before the namespace goes.
struct Rig {
    served: Served,
    ns: Netns,
    device_ip: String,
    peer_ip: String,
}

fn rig(tag: &str, target: &Target, subnet: u8) -> Rig {
    let ns = Netns::new(tag);
    let (device_ip, peer_ip) = (
        format!("192.168.{subnet}.200"),
        format!("192.168.{subnet}.1"),
    );
    ns.add_ipv4(&format!("{device_ip}/24"), &format!("{peer_ip}/24"));
    let opts = ServeOptions {
        profile: target.profile.into(),
        name: NAME.into(),
        ..ServeOptions::new(ns.root_if())
    };
    let served = start(&opts).expect("serve pnio on the veth pair");
    assert_eq!(
        served.rpc_addr().map(|a| a.to_string()),
        Some(format!("{device_ip}:34964"))
    );
    assert_eq!(served.mac().to_string(), target.mac, "{}", target.profile);
    Rig {
        served,
        ns,
        device_ip,
        peer_ip,
    }
}

/// The interop venv's python with pnio_dcp and scapy's PROFINET layers, or the test skips
/// (fails in strict mode).
fn python(why: &str) -> Option<PathBuf> {
    interop_python(&["pnio_dcp", "scapy.contrib.pnio_rpc"], why)
}

/// Runs `tests/interop/SCRIPT ARGS… --deadline DEADLINE` inside the namespace; the JSON line
/// of each operation. The script ends itself at its deadline; should it not, it is killed 15 s
/// later and the test fails.
fn peer(ns: &Netns, py: &Path, script: &str, args: &[String], deadline: u64) -> Vec<Value> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/interop")
        .join(script);
    let t = Instant::now();
    let mut child = ns
        .command(py)
        .arg(path)
        .args(args)
        .args(["--deadline", &deadline.to_string()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the peer starts");
    let drain = |mut r: Box<dyn Read + Send>| {
        std::thread::spawn(move || {
            let mut s = String::new();
            let _ = r.read_to_string(&mut s);
            s
        })
    };
    let out = drain(Box::new(child.stdout.take().expect("piped stdout")));
    let err = drain(Box::new(child.stderr.take().expect("piped stderr")));
    let limit = Duration::from_secs(deadline + 15);
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait for the peer") {
            break Some(status);
        }
        if t.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let (stdout, stderr) = (
        out.join().unwrap_or_default(),
        err.join().unwrap_or_default(),
    );
    assert!(
        status.is_some_and(|s| s.success()),
        "{script} {args:?}: {} after {:?}\n{stdout}\n{stderr}",
        status.map_or("killed: did not end by its deadline".into(), |s| s
            .to_string()),
        t.elapsed()
    );
    eprintln!("{script} {args:?} ({:?}):\n{stdout}", t.elapsed());
    stdout
        .lines()
        .filter(|l| l.starts_with('{'))
        .map(|l| serde_json::from_str::<Value>(l).expect("a JSON line"))
        .collect()
}

fn strings(args: &[&str]) -> Vec<String> {
    args.iter().map(|s| s.to_string()).collect()
}

/// One device of an Identify answer as pnio_dcp (and the script, for the blocks pnio_dcp
/// drops) decoded it.
fn assert_identity(d: &Value, t: &Target, name: &str, ip: &str, mask: &str, gateway: &str) {
    let p = t.profile;
    assert_eq!(d["mac"], t.mac, "{p}: {d}");
    assert_eq!(d["name"], name, "{p}: {d}");
    assert_eq!(
        (&d["ip"], &d["netmask"], &d["gateway"]),
        (&ip.into(), &mask.into(), &gateway.into()),
        "{p}: {d}"
    );
    // BlockInfo of the IP block: 1 "IP set" (IEC 61158-6-10).
    assert_eq!(d["ip_block_info"], 1, "{p}: {d}");
    assert_eq!(d["vendor_id"], VENDOR_ID, "{p}: {d}");
    assert_eq!(
        d["device_id"],
        u64::from(device_id(t.product).expect("a PROFINET product")),
        "{p}: {d}"
    );
    // DeviceRole 01h: IO device (BU 0620 §2.5.1).
    assert_eq!(d["device_role"], 1, "{p}: {d}");
    assert_eq!(d["family"], station_type(t.product).unwrap(), "{p}: {d}");
}

#[test]
fn pnio_dcp_identifies_names_and_addresses_the_served_device() {
    let why = "pnio-dcp and scapy DCP against harness serve pnio";
    if !require_root_or_skip(why) {
        return;
    }
    let Some(py) = python(why) else { return };
    for t in &TARGETS {
        let rig = rig("pnio-dcp", t, 47);
        let (ns, mac) = (&rig.ns, t.mac);
        let new_ip = "192.168.47.201";
        let gateway = "192.168.47.254";
        let mask = "255.255.255.0";
        let mut args = strings(&[&rig.peer_ip, "--timeout", "1", "identify-all"]);
        args.extend(strings(&["identify", mac, "get-name", mac, "get-ip", mac]));
        args.extend(strings(&["set-name", mac, RENAMED]));
        args.extend(strings(&["set-ip", mac, new_ip, mask, gateway]));
        args.extend(strings(&["identify-all"]));
        let r = peer(ns, &py, "pnio_dcp_peer.py", &args, 60);
        let p = t.profile;
        assert_eq!(r.len(), 7, "{p}: {r:#?}");
        for line in &r {
            assert_eq!(line["ok"], true, "{p}: {line}");
        }
        // The one device on the link, as served: its name, the interface's address and prefix.
        assert_eq!(r[0]["count"], 1, "{p}: {}", r[0]);
        assert_identity(
            &r[0]["devices"][0],
            t,
            NAME,
            &rig.device_ip,
            mask,
            "0.0.0.0",
        );
        assert_identity(
            &r[1]["devices"][0],
            t,
            NAME,
            &rig.device_ip,
            mask,
            "0.0.0.0",
        );
        assert_eq!(r[2]["name"], NAME, "{p}: {}", r[2]);
        assert_eq!(r[3]["ip"], rig.device_ip.as_str(), "{p}: {}", r[3]);
        // Set NameOfStation and IP: BlockError 0 in the Control response.
        for line in &r[4..6] {
            assert_eq!(line["code"], 0, "{p}: {line}");
        }
        // The next Identify shows both.
        assert_eq!(r[6]["count"], 1, "{p}: {}", r[6]);
        assert_identity(&r[6]["devices"][0], t, RENAMED, new_ip, mask, gateway);

        // scapy's DCP layers, an independent parser: an Identify by the new name finds the
        // device, one by the old name nothing (a device answers only a name that is its own).
        let args = strings(&[
            "--iface",
            ns.ns_if(),
            "--timeout",
            "1",
            "dcp-identify",
            RENAMED,
            "dcp-identify",
            NAME,
        ]);
        let r = peer(ns, &py, "scapy_pnio_peer.py", &args, 30);
        assert_eq!(r.len(), 2, "{p}: {r:#?}");
        assert_eq!(
            (&r[0]["ok"], &r[0]["count"]),
            (&true.into(), &1.into()),
            "{p}: {}",
            r[0]
        );
        let d = &r[0]["devices"][0];
        assert_eq!(d["mac"], mac, "{p}: {d}");
        assert_eq!(d["name"], RENAMED, "{p}: {d}");
        assert_eq!(
            (&d["ip"], &d["gateway"]),
            (&new_ip.into(), &gateway.into()),
            "{p}: {d}"
        );
        assert_eq!(
            (&d["vendor_id"], &d["device_id"]),
            (
                &VENDOR_ID.into(),
                &u64::from(device_id(t.product).unwrap()).into()
            ),
            "{p}: {d}"
        );
        assert_eq!(
            (&r[1]["count"], &r[1]["error"]),
            (&0.into(), &"no device answered".into()),
            "{p}: {}",
            r[1]
        );

        let stats = rig.served.stats();
        assert_eq!(stats.datagrams_in, 0, "{p}: {stats:?}");
        assert!(stats.frames_in >= 8, "{p}: {stats:?}");
        drop(rig);
    }
}

/// The next line, which must be operation `op`'s.
fn take<'a>(r: &mut std::slice::Iter<'a, Value>, op: &str, profile: &str) -> &'a Value {
    let line = r
        .next()
        .unwrap_or_else(|| panic!("{profile}: no line for {op}"));
    assert_eq!(line["op"], op, "{profile}: {line}");
    line
}

/// The fields of a reply's first block (IODWriteResHeader, IODReadResHeader, IODControlRes).
fn fields(line: &Value) -> &Value {
    &line["blocks"][0]["fields"]
}

#[test]
fn scapy_connects_reads_and_writes_records_and_releases() {
    let why = "scapy's PROFINET layers against harness serve pnio";
    if !require_root_or_skip(why) {
        return;
    }
    let Some(py) = python(why) else { return };
    for t in &TARGETS {
        let rig = rig("pnio-scapy", t, 48);
        let p = t.profile;
        let id = format!("{:#06x}", device_id(t.product).unwrap());
        let mut args = strings(&[
            "--ip",
            &rig.device_ip,
            "--iface",
            rig.ns.ns_if(),
            "--vendor-id",
            "0x0538",
            "--device-id",
            &id,
            "--timeout",
            "2",
            // RT_CLASS_1 (the peer's IOCRProperties) frames are C000h…FBFFh.
            "--output-frame-id",
            "0xC001",
            // The peer sends no output frames: a watchdog of 1000 × 32 ms keeps the AR up
            // through the run once it exchanges data. The data hold time may not pass 1.92 s
            // (IEC 61158-6-10): 60 × 32 ms.
            "--watchdog-factor",
            "1000",
            "--data-hold-factor",
            "60",
        ]);
        for s in t.layout {
            args.extend(strings(&["--submodule", s]));
        }
        let s = FI1_SLOT;
        args.extend(strings(&[
            "dcp-identify",
            "connect",
            "prm-end",
            "appl-ready",
        ]));
        args.extend(strings(&["write", "101", s, "1", P102_ORDER]));
        for _ in 0..6 {
            args.extend(strings(&["read", "101", s, "1"]));
        }
        // Refusals: slot 1 takes no records, there is no record 120, record 101 is 8 bytes.
        args.extend(strings(&["read", "101", "1", "1", "read", "120", s, "1"]));
        args.extend(strings(&["write", "101", s, "1", "244E01"]));
        let bench = 1000;
        if t.product == Product::Sk550p {
            args.extend(strings(&["bench-read", &bench.to_string(), "101", s, "1"]));
            args.push(P102_ORDER.into());
        }
        args.extend(strings(&["release", "read", "101", s, "1"]));
        // As an engineering tool: a DeviceAccess AR, I&M0 of the DAP read in it, Release;
        // then I&M0 by ReadImplicit, without any AR.
        args.extend(strings(&[
            "device-access",
            "read",
            "0xAFF0",
            "0",
            "1",
            "release",
            "read-implicit",
            "0xAFF0",
            "0",
            "1",
        ]));
        let r = peer(&rig.ns, &py, "scapy_pnio_peer.py", &args, 90);
        let mut r = r.iter();
        let mut next = |op: &str| take(&mut r, op, p);

        // DCP Identify All, parsed by scapy.
        let l = next("dcp-identify");
        assert_eq!(
            (&l["ok"], &l["count"]),
            (&true.into(), &1.into()),
            "{p}: {l}"
        );
        let d = &l["devices"][0];
        assert_eq!(
            (&d["mac"], &d["name"]),
            (&t.mac.into(), &NAME.into()),
            "{p}: {d}"
        );
        assert_eq!(d["ip"], rig.device_ip.as_str(), "{p}: {d}");
        assert_eq!(
            d["device_id"],
            u64::from(device_id(t.product).unwrap()),
            "{p}: {d}"
        );

        // Connect: every block parsed, the AR as asked, no module difference.
        let l = next("connect");
        assert_eq!(
            (&l["ok"], &l["pnio_status"]),
            (&true.into(), &"00000000".into()),
            "{p}: {l}"
        );
        assert_eq!(l["responder_mac"], t.mac, "{p}: {l}");
        // CMResponderUDPRTPort: 8892h.
        assert_eq!(l["responder_udp_rt_port"], 0x8892, "{p}: {l}");
        assert_eq!(l["module_diff"], serde_json::json!([]), "{p}: {l}");
        let types: Vec<&Value> = l["blocks"]
            .as_array()
            .expect("blocks")
            .iter()
            .map(|b| &b["type"])
            .collect();
        assert_eq!(types, ["8101", "8102", "8102", "8103"], "{p}: {l}");
        assert_eq!(l["frame_ids"]["output"], 0xC001, "{p}: {l}");
        // The controller's input FrameID, as proposed: RT_CLASS_1's, as declared.
        assert_eq!(l["frame_ids"]["input"], 0xC000, "{p}: {l}");
        let ar = l["ar_uuid"].clone();

        // PrmEnd: IODControlRes (8110h) with Done.
        let l = next("prm-end");
        assert_eq!(l["ok"], true, "{p}: {l}");
        assert_eq!(l["blocks"][0]["type"], "8110", "{p}: {l}");
        assert_eq!(fields(l)["ControlCommand_Done"], 1, "{p}: {l}");

        // The device's ApplicationReady (0112h) to the controller's UDP 34964, in this AR;
        // scapy's answer taken: the input frames then say "run".
        let l = next("appl-ready");
        assert_eq!(l["ok"], true, "{p}: {l}");
        assert_eq!(l["block_type"], "0112", "{p}: {l}");
        assert_eq!(l["request_ar_uuid"], ar, "{p}: {l}");
        assert_eq!(
            l["request_from"],
            format!("{}:34964", rig.device_ip),
            "{p}: {l}"
        );
        // The call goes to the controller's object (CMInitiatorObjectUUID) and interface.
        assert_eq!(
            l["rpc_object"], "dea00000-6c97-11d1-8271-000100000000",
            "{p}: {l}"
        );
        assert_eq!(
            l["rpc_if_id"], "dea00002-6c97-11d1-8271-00a02442df7d",
            "{p}: {l}"
        );
        assert_eq!(l["response_block"], "8112", "{p}: {l}");
        assert_eq!(
            (&l["input_frame_id"], &l["input_run"]),
            (&0xC000.into(), &true.into()),
            "{p}: {l}"
        );

        // The P102 order written to record 101 in FI 1's slot.
        let l = next("write");
        assert_eq!(
            (&l["ok"], &l["record_status"]),
            (&true.into(), &"00000000".into()),
            "{p}: {l}"
        );
        let f = fields(l);
        assert_eq!(
            (&f["index"], &f["slotNumber"], &f["subslotNumber"]),
            (&101.into(), &3.into(), &1.into()),
            "{p}: {l}"
        );
        assert_eq!(f["recordDataLength"], 8, "{p}: {l}");

        // Reads: "Read Response (−)" until the order is processed, then its answer once, then
        // (−) again (no order pending).
        let reads: Vec<&Value> = (0..6).map(|_| next("read")).collect();
        let answered: Vec<usize> = (0..reads.len())
            .filter(|&i| reads[i]["pnio_status"] == "00000000")
            .collect();
        assert_eq!(answered.len(), 1, "{p}: {reads:#?}");
        for (i, l) in reads.iter().enumerate() {
            assert!(l["parse_issues"].is_null(), "{p}: {l}");
            assert_eq!(fields(l)["index"], 101, "{p}: {l}");
            if i == answered[0] {
                assert_eq!(l["data"], P102_ANSWER, "{p}: {l}");
                assert_eq!(l["record_length"], 8, "{p}: {l}");
            } else {
                assert_eq!(l["pnio_status"], BUSY, "{p}: {l}");
                assert_eq!(l["record_length"], 0, "{p}: {l}");
            }
        }

        // Refusals (IEC 61158-6-10 PNIORW): B2h invalid slot, B0h invalid index, B1h write
        // length error, each in a header scapy parses.
        for (status, what) in [("DE80B200", "slot 1"), ("DE80B000", "record 120")] {
            let l = next("read");
            assert_eq!(l["pnio_status"], status, "{p}: {what}: {l}");
            assert!(l["parse_issues"].is_null(), "{p}: {l}");
            assert_eq!(l["blocks"][0]["type"], "8009", "{p}: {l}");
        }
        let l = next("write");
        assert_eq!(
            (&l["pnio_status"], &l["record_status"]),
            (&"DF80B100".into(), &"DF80B100".into()),
            "{p}: {l}"
        );
        assert!(l["parse_issues"].is_null(), "{p}: {l}");

        if t.product == Product::Sk550p {
            // One order, then reads back to back, each built and parsed by scapy: exactly one
            // answer (the P102 one), every other read (−).
            let l = next("bench-read");
            assert_eq!(l["ok"], true, "{p}: {l}");
            assert_eq!(l["write"]["record_status"], "00000000", "{p}: {l}");
            assert_eq!(
                (&l["answered"], &l["parse_errors"]),
                (&bench.into(), &0.into()),
                "{p}: {l}"
            );
            assert_eq!(l["statuses"]["00000000"], 1, "{p}: {l}");
            assert_eq!(l["statuses"][BUSY], bench - 1, "{p}: {l}");
            assert_eq!(l["first_data"], P102_ANSWER, "{p}: {l}");
            println!(
                "scapy record reads against the served {p} over a veth pair: {} reads/s ({bench} reads in {} s)",
                l["reads_per_s"], l["seconds"]
            );
        }

        // Release: ReleaseBlockRes (8114h) with Done; the AR is gone: a read in it is refused
        // (DE 81 40 05: Read, PNIO, CMRPC, AR UUID unknown).
        let l = next("release");
        assert_eq!(l["ok"], true, "{p}: {l}");
        assert_eq!(l["blocks"][0]["type"], "8114", "{p}: {l}");
        assert_eq!(fields(l)["ControlCommand_Done"], 1, "{p}: {l}");
        let l = next("read");
        assert_eq!(l["pnio_status"], "DE814005", "{p}: {l}");

        // The DeviceAccess AR (IOSAR, ARProperties.DeviceAccess): the ARBlockRes alone, as
        // scapy parses it; I&M0 (block 0020h, 56 bytes after type and length, vendor 0538h)
        // read in it; Release with Done. ReadImplicit then reads the same record.
        let l = next("device-access");
        assert_eq!(l["ok"], true, "{p}: {l}");
        assert_eq!(l["block_types"], serde_json::json!(["8101"]), "{p}: {l}");
        for op in ["read", "release", "read-implicit"] {
            let l = next(op);
            assert_eq!(l["ok"], true, "{p}: {op}: {l}");
            if op != "release" {
                let data = l["data"].as_str().unwrap_or_default().to_ascii_lowercase();
                assert!(data.starts_with("002000380100"), "{p}: {op}: {l}");
                assert_eq!(l["record_length"], 60, "{p}: {op}: {l}");
            }
        }
        drop(next);
        assert!(r.next().is_none(), "{p}: more lines than operations");

        let stats = rig.served.stats();
        assert!(
            stats.datagrams_in >= 14 && stats.datagrams_out >= 14,
            "{p}: {stats:?}"
        );
        drop(rig);
    }
}
