//! What an `enip:` step can do to a real device ([`crate::effect`]), decoded from the request
//! it sends: a Set_Attribute_Single to a NORD parameter class writes that parameter (class 100
//! the module's own, 100 + n FI n: BU 2100 §6.3, BU 0620 §2.3.5), one to an assembly (class
//! 04h) writes output process data, an Unconnected_Send or Multiple_Service carries further
//! requests. A request to write that does not decode counts as able to make a motor turn.

use proto::enip::cip::{class, MrRequest, Service};
use proto::enip::cm::UnconnectedSend;
use proto::enip::cpf::item_type::{CONNECTED_DATA, UNCONNECTED_DATA};
use proto::enip::cpf::Item;
use proto::enip::encap::SendData;
use proto::enip::epath::EPath;
use proto::nord::Inverter;

use super::step::EnipStep;
use crate::effect::{self, Effect};

/// Encapsulation commands that carry CIP requests: SendRRData, SendUnitData.
const SEND_RR_DATA: u16 = 0x6F;
const SEND_UNIT_DATA: u16 = 0x70;
/// Encapsulation header length (CIP Vol 2 §2-3.2).
const HEADER: usize = 24;
/// Interface handle and timeout before the item list of SendRRData/SendUnitData.
const SEND_DATA_HEAD: usize = 6;
/// Set_Attribute_List (CIP Vol 1 Appendix A).
const SET_ATTRIBUTE_LIST: u8 = 0x04;
/// Services that write nothing the device keeps and start nothing: the Get services, the
/// Connection Manager's (the data of an I/O connection are the binding's `process` words).
const HARMLESS: [Service; 6] = [
    Service::GET_ATTRIBUTES_ALL,
    Service(0x03),
    Service::GET_ATTRIBUTE_SINGLE,
    Service::FORWARD_CLOSE,
    Service::FORWARD_OPEN,
    Service::LARGE_FORWARD_OPEN,
];

/// What the step can do.
pub(super) fn of(step: &EnipStep) -> Effect {
    match step {
        EnipStep::Raw { bytes, .. } => encapsulation(bytes),
        EnipStep::Mr { bytes, .. } => request_bytes(bytes),
        EnipStep::Request {
            service,
            path,
            data,
            ..
        } => match EPath::parse(path) {
            Ok(p) => request(*service, &p, data),
            Err(_) => undecoded(*service, &[path.as_slice(), data].concat()),
        },
        EnipStep::ForwardOpen(_) | EnipStep::StopIo { .. } | EnipStep::Run(_) => Effect::NONE,
    }
}

/// An encapsulation message as written: only SendRRData and SendUnitData carry requests.
fn encapsulation(bytes: &[u8]) -> Effect {
    let command = match bytes {
        [a, b, ..] => u16::from_le_bytes([*a, *b]),
        _ => return Effect::NONE,
    };
    if command != SEND_RR_DATA && command != SEND_UNIT_DATA {
        return Effect::NONE;
    }
    let data = bytes.get(HEADER..).unwrap_or_default();
    match SendData::parse(data) {
        Ok(send) => send
            .cpf
            .items
            .iter()
            .map(|item| match item {
                Item::UnconnectedData(d) => request_bytes(d),
                Item::ConnectedData(d) => connected(d),
                _ => Effect::NONE,
            })
            .fold(Effect::NONE, Effect::and),
        Err(_) => malformed_items(data.get(SEND_DATA_HEAD..).unwrap_or_default()),
    }
}

/// A connected message starts with its sequence count.
fn connected(item: &[u8]) -> Effect {
    request_bytes(item.get(2..).unwrap_or_default())
}

/// The item list of a SendRRData/SendUnitData that does not parse (a count beyond the items,
/// a length beyond the data): the items walked as far as the bytes go, and each data item's
/// request as far as it is there — what a lenient target would take.
fn malformed_items(list: &[u8]) -> Effect {
    let word = |at: usize| {
        list.get(at..at + 2)
            .map(|b| u16::from_le_bytes([b[0], b[1]]))
    };
    let mut effect = Effect::NONE;
    let mut at = 2;
    while let (Some(kind), Some(len)) = (word(at), word(at + 2)) {
        let start = at + 4;
        let end = (start + usize::from(len)).min(list.len());
        let item = list.get(start..end).unwrap_or_default();
        effect = effect.and(match kind {
            UNCONNECTED_DATA => request_bytes(item),
            CONNECTED_DATA => connected(item),
            _ => Effect::NONE,
        });
        at = end;
    }
    effect
}

/// A message-router request as bytes.
fn request_bytes(bytes: &[u8]) -> Effect {
    match MrRequest::parse(bytes) {
        Ok(r) => request(r.service, &r.path, &r.data),
        Err(_) => match bytes.split_first() {
            Some((service, rest)) => undecoded(*service, rest),
            None => Effect::NONE,
        },
    }
}

/// A request whose path does not decode: harmless only if its service is.
fn undecoded(service: u8, rest: &[u8]) -> Effect {
    if HARMLESS.contains(&Service(service)) || rest.iter().all(|b| *b == 0) {
        Effect::NONE
    } else {
        Effect::motion(format!(
            "a request of service {service:02X}h whose path the harness cannot decode"
        ))
    }
}

/// A request: service, path, data.
fn request(service: u8, path: &EPath, data: &[u8]) -> Effect {
    let class = path.class_id();
    let service = Service(service);
    if HARMLESS.contains(&service) {
        return Effect::NONE;
    }
    match service {
        Service::SET_ATTRIBUTE_SINGLE => match (class, path.attribute_id()) {
            (Some(class::ASSEMBLY), _) => effect::output_data(
                &format!(
                    "Set_Attribute_Single of assembly {}",
                    path.instance_id().unwrap_or(0)
                ),
                data,
            ),
            (Some(c @ 100..=108), Some(attribute)) => parameter(c, attribute),
            // Any other attribute set may be kept (the interface's own parameters P15x/P16x
            // "can be set and saved", BU 2100 §7.1).
            _ => Effect::eeprom(1),
        },
        Service::SET_ATTRIBUTES_ALL | Service(SET_ATTRIBUTE_LIST) => match class {
            Some(class::ASSEMBLY) => effect::output_data("a Set_Attribute of an assembly", data),
            Some(100..=108) => Effect::motion(
                "sets parameters of a NORD parameter class the harness does not decode one by one",
            )
            .and(Effect::eeprom(1)),
            _ => Effect::eeprom(1),
        },
        Service::UNCONNECTED_SEND => match UnconnectedSend::parse(data) {
            Ok(u) => request_bytes(&u.request),
            Err(_) => undecoded(service.0, data),
        },
        Service::MULTIPLE_SERVICE => multiple(data),
        // Reset type 1 and 2 return to the factory defaults (CIP Vol 1 §5A-2.3).
        Service::RESET if matches!(data.first(), Some(1 | 2)) => Effect::eeprom(1),
        Service::RESET => Effect::NONE,
        _ if matches!(class, Some(class::ASSEMBLY | 100..=108)) => Effect::motion(format!(
            "service {:02X}h to an assembly or a NORD parameter class",
            service.0
        )),
        _ => Effect::NONE,
    }
}

/// A parameter of a NORD parameter class, written with Set_Attribute_Single: the attribute is
/// the parameter number. Class 100 is a module's own parameters; 101 is FI 1 (on an SK 550P
/// its interface parameters too, counted as the inverter's, conservatively).
fn parameter(class: u16, attribute: u16) -> Effect {
    let fi = Inverter::new(i64::from(class - 100)).ok();
    effect::parameter_write(fi, attribute, false)
}

/// A Multiple_Service request: a count, offsets from the count, the requests (CIP Vol 1
///
fn multiple(data: &[u8]) -> Effect {
    let word = |at: usize| {
        data.get(at..at + 2)
            .map(|b| usize::from(u16::from_le_bytes([b[0], b[1]])))
    };
    let Some(count) = word(0) else {
        return Effect::NONE;
    };
    let offsets: Option<Vec<usize>> = (0..count).map(|k| word(2 + 2 * k)).collect();
    let Some(mut offsets) = offsets else {
        return undecoded(Service::MULTIPLE_SERVICE.0, data);
    };
    offsets.push(data.len());
    offsets
        .windows(2)
        .map(|w| match data.get(w[0]..w[1]) {
            Some(r) => request_bytes(r),
            None => undecoded(Service::MULTIPLE_SERVICE.0, data),
        })
        .fold(Effect::NONE, Effect::and)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mr(hex: &str) -> Effect {
        let bytes: Vec<u8> = hex
            .split_whitespace()
            .map(|t| u8::from_str_radix(t, 16).unwrap())
            .collect();
        request_bytes(&bytes)
    }

    #[test]
    fn parameter_writes_by_class_and_attribute() {
        // P102 of FI 1: class 101 (65h), instance 0, attribute 102 (66h), value 200.
        assert_eq!(mr("10 03 20 65 24 00 30 66 C8 00"), Effect::eeprom(1));
        // P509 of FI 2: class 102, attribute 509 (01FDh, a 16-bit attribute segment 31h).
        let e = mr("10 04 20 66 24 00 31 00 FD 01 08 00");
        assert!(e.motion.unwrap().starts_with("P509"));
        // P509 of the module itself (class 100) is not the inverter's.
        assert_eq!(mr("10 04 20 64 24 00 31 00 FD 01 08 00"), Effect::eeprom(1));
        // Reads: nothing.
        assert_eq!(mr("0E 03 20 65 24 00 30 66"), Effect::NONE);
    }

    #[test]
    fn assembly_writes_are_output_data() {
        // Set_Attribute_Single assembly 100 attribute 3: 047Eh in FI 1's control word.
        let e = mr("10 03 20 04 24 64 30 03 7E 04 00 00");
        assert!(e.motion.is_some());
        assert_eq!(mr("10 03 20 04 24 64 30 03 00 00 00 00"), Effect::NONE);
    }

    #[test]
    fn requests_inside_unconnected_send_and_raw_encapsulation() {
        // Unconnected_Send to the Connection Manager carrying the P509 write of FI 2.
        let inner = "10 04 20 66 24 00 31 00 FD 01 08 00";
        let e = mr(&format!(
            "52 02 20 06 24 01 0A 0E 0C 00 {inner} 01 00 01 00"
        ));
        assert!(e.motion.is_some(), "{e:?}");
        // SendRRData: header, interface handle, timeout, null item, unconnected data item.
        let mut raw = vec![0x6F, 0, 22, 0];
        raw.extend([0u8; 20]);
        raw.extend([0, 0, 0, 0, 0, 0, 2, 0, 0, 0, 0, 0, 0xB2, 0, 10, 0]);
        raw.extend([0x10, 0x03, 0x20, 0x65, 0x24, 0x00, 0x30, 0x66, 0xC8, 0x00]);
        assert_eq!(encapsulation(&raw), Effect::eeprom(1));
        // The suites' malformed SendRRData: no request, or a read in an item list that lies.
        assert_eq!(
            encapsulation(&[0x6F, 0, 0x18, 0, 0, 0, 0, 0, 0, 0]),
            Effect::NONE
        );
        let mut lying = raw[..24].to_vec();
        lying.extend([0, 0, 0, 0, 0, 0, 3, 0, 0, 0, 0, 0, 0xB2, 0, 40, 0]);
        lying.extend([0x0E, 0x03, 0x20, 0x01, 0x24, 0x01, 0x30, 0x01]);
        assert_eq!(encapsulation(&lying), Effect::NONE);
        // The same list carrying a write still counts.
        let n = lying.len();
        lying[n - 8] = 0x10;
        lying.extend([0xC8, 0x00]);
        assert_eq!(encapsulation(&lying), Effect::eeprom(1));
        // Other commands (RegisterSession) carry none either.
        assert_eq!(encapsulation(&[0x65, 0, 4, 0]), Effect::NONE);
    }
}
