//! Compute functions of the `tables` theme: error tables, SDO aborts, device-name rules.

use proto::nord::errors::{self, SdoAbort};
use proto::nord::nmt::{self, EcState, PlEvent, PlState};
use proto::nord::{led, rules, Protocol};
use serde_json::{json, Value};

use super::{Args, ComputeError, ComputeFn, Ctx};

fn sdo_abort(_: &Ctx, a: &Args) -> Result<Value, ComputeError> {
    let protocol = match a.str("protocol")? {
        "ethercat" => Protocol::Ethercat,
        "powerlink" => Protocol::Powerlink,
        "ds301" => {
            // The standard's own list (CiA 301 and EPSG DS 301 share the codes), against
            // which the manuals' printed lists are checked.
            let code = proto::ecat::coe::SdoAbortCode(a.int("code")? as u32);
            return Ok(match code.name() {
                Some(t) => json!({ "listed": true, "text": t }),
                None => json!({ "listed": false }),
            });
        }
        p => {
            return Err(ComputeError::BadArg {
                arg: "protocol".into(),
                why: format!("`{p}` has no SDO abort list (ethercat, powerlink, ds301)"),
            })
        }
    };
    let code = a.int("code")? as u32;
    Ok(match SdoAbort(code).describe(protocol) {
        Some(t) => json!({ "listed": true, "text": t }),
        None => json!({ "listed": false }),
    })
}

fn comm_error(_: &Ctx, a: &Args) -> Result<Value, ComputeError> {
    let ds402 = a.int("ds402")? as u16;
    let e = errors::COMM_ERRORS
        .iter()
        .find(|e| e.ds402 == ds402)
        .ok_or_else(|| ComputeError::Refused(format!("{ds402:04X}h is not in BU 0620 §5.3")))?;
    Ok(json!({ "p700": e.p700, "text": e.text, "profinet_alarm": errors::profinet_alarm(e.p700) }))
}

fn ethertype(_: &Ctx, a: &Args) -> Result<Value, ComputeError> {
    use proto::eth::{ethertype_name, ETHERTYPE_ECAT, ETHERTYPE_POWERLINK, ETHERTYPE_PROFINET};
    let value = match a.str("protocol")? {
        "ethercat" => ETHERTYPE_ECAT,
        "powerlink" => ETHERTYPE_POWERLINK,
        "profinet" => ETHERTYPE_PROFINET,
        p => {
            return Err(ComputeError::BadArg {
                arg: "protocol".into(),
                why: format!("`{p}` has no EtherType of its own (ethercat, powerlink, profinet)"),
            })
        }
    };
    Ok(json!({ "value": value, "name": ethertype_name(value) }))
}

fn led_table(_: &Ctx, a: &Args) -> Result<Value, ComputeError> {
    let rows = match a.str("led")? {
        "dev" => &led::DEV,
        "bus" => &led::BUS,
        "ethercat-run" => &led::ETHERCAT_RUN,
        "ethercat-err" => &led::ETHERCAT_ERR,
        "ethernetip-ms" => &led::ETHERNETIP_MS,
        "ethernetip-ns" => &led::ETHERNETIP_NS,
        "powerlink-bs" => &led::POWERLINK_BS,
        "powerlink-be" => &led::POWERLINK_BE,
        "profinet-run" => &led::PROFINET_RUN,
        "profinet-bf" => &led::PROFINET_BF,
        "tu3-pnt-err" => &led::TU3_PNT_ERR,
        "tu3-pnt-ds" => &led::TU3_PNT_DS,
        "tu3-pnt-de" => &led::TU3_PNT_DE,
        other => {
            return Err(ComputeError::BadArg {
                arg: "led".into(),
                why: format!("no LED table `{other}` (dev, bus, ethercat-run, ethercat-err, ethernetip-ms, ethernetip-ns, powerlink-bs, powerlink-be, profinet-run, profinet-bf, tu3-pnt-err, tu3-pnt-ds, tu3-pnt-de)"),
            })
        }
    };
    serde_json::to_value(&rows[..])
        .map(|rows| json!({ "rows": rows }))
        .map_err(|e| ComputeError::Refused(e.to_string()))
}

fn bad(arg: &str, why: String) -> ComputeError {
    ComputeError::BadArg {
        arg: arg.into(),
        why,
    }
}

fn powerlink_nmt(_: &Ctx, a: &Args) -> Result<Value, ComputeError> {
    let s = a.str("state")?;
    let state =
        PlState::from_name(s).ok_or_else(|| bad("state", format!("no POWERLINK state `{s}`")))?;
    let e = a.str("event")?;
    let event = PlEvent::from_name(e).ok_or_else(|| bad("event", format!("no event `{e}`")))?;
    let next =
        nmt::powerlink_next(state, event).map_err(|e| ComputeError::Refused(e.to_string()))?;
    Ok(
        json!({ "to": next.name(), "parameters": next.parameters(), "process_data": next.process_data() }),
    )
}

fn powerlink_be(_: &Ctx, a: &Args) -> Result<Value, ComputeError> {
    let s = a.str("state")?;
    let state =
        PlState::from_name(s).ok_or_else(|| bad("state", format!("no POWERLINK state `{s}`")))?;
    serde_json::to_value(led::powerlink_module_be_red(state))
        .map_err(|e| ComputeError::Refused(e.to_string()))
}

fn nmt_state_code(_: &Ctx, a: &Args) -> Result<Value, ComputeError> {
    if let Some(s) = a.opt_str("state")? {
        let state = PlState::from_name(s)
            .ok_or_else(|| bad("state", format!("no POWERLINK state `{s}`")))?;
        return Ok(json!({ "code": state.p182() }));
    }
    let code = a.int("code")?;
    let entry = nmt::p182(code).ok_or_else(|| {
        ComputeError::Refused(format!("{code} is not a P182 value of BU 2200 §7.1.4"))
    })?;
    Ok(json!({ "code": entry.code, "name": entry.name, "state": entry.state.map(PlState::name) }))
}

fn ethercat_nmt(_: &Ctx, a: &Args) -> Result<Value, ComputeError> {
    let state = |arg: &str| -> Result<EcState, ComputeError> {
        let s = a.str(arg)?;
        EcState::from_name(s).ok_or_else(|| bad(arg, format!("no EtherCAT state `{s}`")))
    };
    let next = nmt::ethercat_next(state("state")?, state("request")?)
        .map_err(|e| ComputeError::Refused(e.to_string()))?;
    Ok(json!({ "to": next.name() }))
}

fn powerlink_error(_: &Ctx, a: &Args) -> Result<Value, ComputeError> {
    if a.raw_present("code") {
        // The rows of one DS-301 code (§5.4.1.2), e.g. 1000h with no P700 number.
        let code = a.int("code")? as u16;
        let rows: Vec<Value> = errors::powerlink_rows(code)
            .map(|e| json!({ "register": e.register, "p700": e.p700, "text": e.text }))
            .collect();
        return Ok(json!({ "code": code, "group": errors::error_group(code), "rows": rows }));
    }
    let p700 = a.int("p700")? as u16;
    // `manual:` names the table's manual: BU 0620 §5.4.1.2 or BU 2200 §8.3.2, which print the
    // same 44 rows.
    if let Some(m) = a
        .opt_str("manual")?
        .filter(|m| !matches!(*m, "BU 0620" | "BU 2200"))
    {
        return Err(bad(
            "manual",
            format!("`{m}` has no POWERLINK error table (BU 0620, BU 2200)"),
        ));
    }
    let e = errors::powerlink_error(p700).ok_or_else(|| {
        ComputeError::Refused(format!(
            "P700 {p700} has no POWERLINK error code in BU 0620 §5.4.1.2 (BU 2200 §8.3.2)"
        ))
    })?;
    Ok(
        json!({ "code": e.code, "register": e.register, "text": e.text, "group": errors::error_group(e.code) }),
    )
}

fn ip_of(a: &Args, name: &str) -> Result<[u8; 4], ComputeError> {
    let text = a.str(name)?;
    let parts: Vec<u8> = text.split('.').filter_map(|p| p.parse().ok()).collect();
    parts
        .try_into()
        .map_err(|_| bad(name, format!("`{text}` is not a dotted IPv4 address")))
}

fn powerlink_ip(_: &Ctx, a: &Args) -> Result<Value, ComputeError> {
    let show = |ip: [u8; 4]| format!("{}.{}.{}.{}", ip[0], ip[1], ip[2], ip[3]);
    if a.raw_present("gateway") {
        return Ok(match rules::powerlink_gateway(ip_of(a, "gateway")?) {
            Ok(()) => json!({ "valid": true }),
            Err(e) => json!({ "valid": false, "rule": e.to_string() }),
        });
    }
    let id = u8::try_from(a.int("node_id")?)
        .map_err(|_| ComputeError::Refused("a node id is one byte".into()))?;
    let (ip, mask) = rules::powerlink_ip(id).map_err(|e| ComputeError::Refused(e.to_string()))?;
    Ok(json!({ "ip": show(ip), "mask": show(mask) }))
}

/// The areas of a POWERLINK object dictionary: EPSG DS 301, "Object Dictionary structure" (as the
/// OPC UA POWERLINK companion specification OPC 30110 §4.1.4 Table 8 reproduces it). BU 2200
/// §3.3 prints a shorter list (00A0h…0FFFh reserved, A000h…AFFFh interface profiles).
const OD_AREAS: &[(u16, u16, &str)] = &[
    (0x0000, 0x0000, "not used"),
    (0x0001, 0x009F, "Data Types"),
    (0x00A0, 0x03FF, "Reserved"),
    (0x0400, 0x04FF, "POWERLINK Specific Data Types"),
    (0x0500, 0x0FFF, "Reserved"),
    (0x1000, 0x1FFF, "Communication Profile Area"),
    (0x2000, 0x5FFF, "Manufacturer Specific Profile Area"),
    (0x6000, 0x9FFF, "Standardised Device Profile Area"),
    (0xA000, 0xBFFF, "Standardised Interface Profile Area"),
    (0xC000, 0xFFFF, "Reserved"),
];

fn od_area(_: &Ctx, a: &Args) -> Result<Value, ComputeError> {
    let index = u16::try_from(a.int("index")?)
        .map_err(|_| ComputeError::Refused("an object index is 16 bits (0…FFFFh)".into()))?;
    let (first, last, area) = OD_AREAS
        .iter()
        .find(|(f, l, _)| (*f..=*l).contains(&index))
        .copied()
        .unwrap_or((0, 0, "not used"));
    Ok(json!({ "area": area, "first": first, "last": last }))
}

/// The POWERLINK device description file of the profile's product (BU 2200 §5.2.1): its name
/// and, with `index`, whether it describes that object (the inverters' parameters at 2800h + P…).
fn xdd_file(c: &Ctx, a: &Args) -> Result<Value, ComputeError> {
    let text = crate::dictionary::xdd::xdd(c.product, 1)
        .map_err(|e| ComputeError::Refused(e.to_string()))?;
    let mut out = json!({ "file": crate::dictionary::xdd::file_name(c.product) });
    if let Some(index) = a.opt_int("index")? {
        out["has_object"] = json!(text.contains(&format!("index=\"{index:04X}\"")));
    }
    Ok(out)
}

/// A module's own error (`p170`, tenths: BU 2200 §8.4, BU 2100 §8.3) or the inverter error a
/// POWERLINK module causes (`p700`, E010, BU 2200 §8.4).
fn module_error(_: &Ctx, a: &Args) -> Result<Value, ComputeError> {
    if let Some(p170) = a.opt_int("p170")? {
        let text = u16::try_from(p170).ok().and_then(errors::module_error);
        return Ok(match text {
            Some(t) => json!({ "listed": true, "text": t }),
            None => json!({ "listed": false }),
        });
    }
    let p700 = a.int("p700")?;
    Ok(
        match errors::POWERLINK_MODULE_E10
            .iter()
            .find(|(v, _)| i64::from(*v) == p700)
        {
            Some((_, t)) => json!({ "listed": true, "text": t }),
            None => json!({ "listed": false }),
        },
    )
}

/// The functions of this theme.
pub(super) const FNS: &[ComputeFn] = &[
    ComputeFn {
        name: "tables.module_error",
        doc: "A module's P170 error (p170, tenths) or the E010 inverter error a POWERLINK module causes (p700): listed, meaning (BU 2200 §8.4, BU 2100 §8.3)",
        run: module_error,
    },
    ComputeFn {
        name: "tables.xdd_file",
        doc: "POWERLINK device description file of the product: name, and with `index` whether it holds that object (BU 2200 §5.2.1)",
        run: xdd_file,
    },
    ComputeFn {
        name: "tables.od_area",
        doc: "Area of a POWERLINK object index (EPSG DS 301 object dictionary structure; BU 2200 §3.3)",
        run: od_area,
    },
    ComputeFn {
        name: "tables.sdo_abort",
        doc: "Is an SDO abort code in the protocol's list, and its text (BU 0620 §2.2.7.2, §2.4.7; ds301: the standard's)",
        run: sdo_abort,
    },
    ComputeFn {
        name: "tables.comm_error",
        doc: "P700 error and PROFINET alarm of a DS402 code (BU 0620 §5.3, §5.4.2)",
        run: comm_error,
    },
    ComputeFn {
        name: "tables.profinet_alarm",
        doc: "PROFINET alarm number of a P700 value: 100h + P700 (BU 0620 §5.4.2)",
        run: |_: &Ctx, a: &Args| {
            let p700 = match a.opt_str("event")? {
                Some("lost-inverter") => errors::LOST_INVERTER.get(),
                Some(e) => {
                    return Err(bad(
                        "event",
                        format!("`{e}` is not an event (lost-inverter)"),
                    ))
                }
                None => a.int("p700")? as u16,
            };
            Ok(json!({ "alarm": errors::profinet_alarm(p700) }))
        },
    },
    ComputeFn {
        name: "tables.bus_protocol",
        doc: "What a P899 / P870 value means (BU 0620 §3.3, §4.1, §4.3)",
        run: |_: &Ctx, a: &Args| {
            let value = a.int("value")?;
            let (_, p899, p870) = proto::nord::product::BUS_PROTOCOL_VALUES
                .iter()
                .find(|(v, _, _)| i64::from(*v) == value)
                .ok_or_else(|| ComputeError::Refused(format!("{value} is not in 0…4")))?;
            Ok(json!({ "p899": p899, "p870": p870 }))
        },
    },
    ComputeFn {
        name: "tables.powerlink_error",
        doc: "POWERLINK error code and register of a P700 error, or (`code`) the rows of a code (BU 0620 §5.4.1.2; `manual: BU 2200`: §8.3.2, the same table)",
        run: powerlink_error,
    },
    ComputeFn {
        name: "tables.powerlink_ip",
        doc: "POWERLINK IP address of a node id, or whether a gateway is allowed (BU 0620 §3.7.3)",
        run: powerlink_ip,
    },
    ComputeFn {
        name: "tables.addressing_mode",
        doc: "EtherNet/IP addressing mode of a P856/P165 value (BU 0620 §4.2.2, BU 2100 §7.1.2)",
        run: |_: &Ctx, a: &Args| {
            let v = a.int("value")?;
            let m = rules::AddressingMode::from_value(v).ok_or_else(|| {
                ComputeError::Refused(format!("{v} is not an addressing mode (0…2)"))
            })?;
            Ok(json!({ "mode": m }))
        },
    },
    ComputeFn {
        name: "tables.powerlink_nmt",
        doc: "POWERLINK NMT: next state on an event (BU 0620 §2.4.4)",
        run: powerlink_nmt,
    },
    ComputeFn {
        name: "tables.powerlink_be",
        doc: "What a lit red BE LED of a POWERLINK module means in an NMT state (BU 2200 §6.2)",
        run: powerlink_be,
    },
    ComputeFn {
        name: "tables.nmt_state_code",
        doc:
            "P182 NMT State: the code of a POWERLINK state, or the name of a code (BU 2200 §7.1.4)",
        run: nmt_state_code,
    },
    ComputeFn {
        name: "tables.ethercat_nmt",
        doc: "EtherCAT state machine: may the master request a state (BU 0620 §2.2.5)",
        run: ethercat_nmt,
    },
    ComputeFn {
        name: "tables.node_id",
        doc: "POWERLINK node id class (BU 0620 §2.4.3.1)",
        run: |_: &Ctx, a: &Args| {
            let id = u8::try_from(a.int("id")?)
                .map_err(|_| ComputeError::Refused("a node id is one byte (0..255)".into()))?;
            serde_json::to_value(nmt::node_id(id)).map_err(|e| ComputeError::Refused(e.to_string()))
        },
    },
    ComputeFn {
        name: "tables.led",
        doc: "An LED table: pattern and meaning per row (BU 0620 §5.5)",
        run: led_table,
    },
    ComputeFn {
        name: "tables.tu3_update_cycle",
        doc: "Process-data update cycle of an SK TU3-EIP over the system bus per inverter count, µs (BU 2100 §4.3)",
        run: |_: &Ctx, a: &Args| {
            let n = a.int("inverters")?;
            let us = u8::try_from(n)
                .ok()
                .and_then(proto::nord::eip::tu3_update_cycle_us)
                .ok_or_else(|| bad("inverters", format!("{n}: an SK TU3-EIP takes 1…8")))?;
            Ok(json!({ "us": us }))
        },
    },
    ComputeFn {
        name: "tables.update_cycle",
        doc: "Process-data update cycle over the system bus of the product with `inverters` inverters: the SK TU3-EIP's table, else at least 5 ms (kind table|at_least, us; BU 0620 §2.5.1, BU 2100 §4.3)",
        run: |c: &Ctx, a: &Args| {
            let n = a.int("inverters")?;
            let cycle = u8::try_from(n)
                .map_err(|_| bad("inverters", format!("{n}: give 1…8")))
                .and_then(|n| {
                    proto::nord::can::update_cycle(c.product, n)
                        .map_err(|e| ComputeError::Refused(e.to_string()))
                })?;
            serde_json::to_value(cycle).map_err(|e| ComputeError::Refused(e.to_string()))
        },
    },
    ComputeFn {
        name: "tables.ethernet_frame",
        doc: "The Ethernet II frame a bus travels in: EtherType, data 46…1500 bytes, frame 64…1518 bytes with FCS (IEEE 802.3; BU 2100 §3.3)",
        run: |_: &Ctx, a: &Args| {
            use proto::eth;
            let protocol = a.str("protocol")?;
            let ethertype = match protocol {
                // EtherNet/IP: TCP and UDP over IPv4.
                "enip" => eth::ETHERTYPE_IPV4,
                "ecat" => eth::ETHERTYPE_ECAT,
                "powerlink" => eth::ETHERTYPE_POWERLINK,
                "profinet" => eth::ETHERTYPE_PROFINET,
                other => return Err(bad("protocol", format!("`{other}`: enip, ecat, powerlink or profinet"))),
            };
            let fcs = 4;
            Ok(json!({
                "ethertype": ethertype,
                "min_data": eth::MIN_FRAME_LEN - eth::HEADER_LEN,
                "max_data": eth::MAX_FRAME_LEN - eth::HEADER_LEN,
                "min_frame": eth::MIN_FRAME_LEN + fcs,
                "llc": false,
            }))
        },
    },
    ComputeFn {
        name: "tables.eip_identity",
        doc: "EtherNet/IP identity of the product: product code, name, revision, EDS file (BU 2100 §5.2.1)",
        run: |c: &Ctx, _: &Args| {
            let id = proto::nord::eip::identity(c.product).ok_or_else(|| {
                ComputeError::Refused(format!("{} has no EtherNet/IP interface", c.product.name()))
            })?;
            Ok(json!({
                "product_code": id.product_code,
                "name": id.name,
                "revision": format!("{}.{}", id.revision.0, id.revision.1),
                "eds_file": id.eds_file,
            }))
        },
    },
    ComputeFn {
        name: "tables.error_group",
        doc: "DS-301 error group of an error code: 00xxh no error … FF00h specific to device (BU 0620 §5.4.1.2)",
        run: |_: &Ctx, a: &Args| {
            let code = u16::try_from(a.int("code")?).map_err(|_| ComputeError::BadArg {
                arg: "code".into(),
                why: "an error code is 16 bits".into(),
            })?;
            Ok(json!({ "group": errors::error_group(code) }))
        },
    },
    ComputeFn {
        name: "tables.ethertype",
        doc: "EtherType of a real-time Ethernet: ethercat 88A4h, powerlink 88ABh, profinet 8892h (BU 0620 §2.2.3, §2.4.3, §2.5.3; IEEE EtherType registry)",
        run: ethertype,
    },
    ComputeFn {
        name: "tables.can_termination",
        doc: "Is the CAN termination of the device at `position` of a system-bus line of `count` devices on (both ends only; BU 0620 §3.9 step 1)",
        run: |_: &Ctx, a: &Args| {
            let byte = |name: &str| {
                u8::try_from(a.int(name)?).map_err(|_| ComputeError::BadArg {
                    arg: name.into(),
                    why: "a position on the line is 1..255".into(),
                })
            };
            let (position, count) = (byte("position")?, byte("count")?);
            match rules::can_termination(position, count) {
                Some(on) => Ok(json!({ "termination": if on { "ON" } else { "OFF" } })),
                None => Err(ComputeError::Refused(format!(
                    "position {position} is not on a line of {count} devices"
                ))),
            }
        },
    },
    ComputeFn {
        name: "tables.device_name",
        doc: "Checks a PROFINET device name against the rules (BU 0620 §3.8.1, P854)",
        run: |_: &Ctx, a: &Args| {
            Ok(match rules::validate_device_name(a.str("name")?) {
                Ok(()) => json!({ "valid": true }),
                Err(e) => json!({ "valid": false, "rule": e.to_string() }),
            })
        },
    },
];

#[cfg(test)]
mod tests {
    use super::OD_AREAS;

    #[test]
    fn od_areas_cover_every_index_once() {
        // EPSG DS 301's areas follow each other from 0000h to FFFFh without gap or overlap.
        let mut next = 0u32;
        for (first, last, _) in OD_AREAS {
            assert_eq!(u32::from(*first), next, "gap or overlap at {first:04X}h");
            next = u32::from(*last) + 1;
        }
        assert_eq!(next, 0x1_0000);
    }
}
