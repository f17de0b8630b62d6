//! Explicit messages: the CIP objects of the adapter and the NORD parameter classes.

use std::net::{Ipv4Addr, SocketAddr};
use std::time::Duration;

use proto::enip::cip::{class, GeneralStatus as GS, MrRequest, MrResponse, Service};
use proto::enip::cm::UnconnectedSend;
use proto::enip::epath::Segment;
use proto::nord::addr::cip_decode_instance;
use proto::nord::params::{Access as ParamAccess, Width};
use proto::nord::{Family, Inverter, ParamNumber, Product};
use proto::wire::Error;

use super::{connections, malformed, Adapter, ClientId};
use crate::link::Unit;
use crate::objects::{abort, Refused};
use crate::store::{AccessError, ParamStore, Persist};
use proto::nord::errors::SdoAbort;

/// The MAC address the simulator shows: NORD's prefix F0:5F:5A (BU 0620 §4.4.1, BU 2100
/// §7.1.4) and a suffix from the product code.
pub(super) fn mac(a: &Adapter) -> [u8; 6] {
    let code = a.identity.product_code.to_be_bytes();
    [0xF0, 0x5F, 0x5A, 0x00, code[0], code[1]]
}

/// Parameter numbers that differ between the SK 550P (P85x/P87x) and the modules (P16x/P18x).
struct IpParams {
    address: u16,
    mask: u16,
    gateway: u16,
    mode: u16,
    present_address: u16,
    present_mask: u16,
    mac: u16,
    active_assembly: u16,
}

fn ip_params(product: Product) -> IpParams {
    match product.family() {
        Family::Integrated => IpParams {
            address: 850,
            mask: 851,
            gateway: 852,
            mode: 856,
            present_address: 875,
            present_mask: 876,
            mac: 878,
            active_assembly: 879,
        },
        Family::Module => IpParams {
            address: 160,
            mask: 161,
            gateway: 164,
            mode: 165,
            present_address: 185,
            present_mask: 186,
            mac: 181,
            active_assembly: 180,
        },
    }
}

fn read4(store: &ParamStore, number: u16) -> [u8; 4] {
    let mut out = [0; 4];
    if let Ok(n) = ParamNumber::new(i64::from(number)) {
        for (i, b) in out.iter_mut().enumerate() {
            let e = proto::nord::ArrayElement::new(i as i64 + 1).ok();
            *b = store.read(n, None, e).unwrap_or(0) as u8;
        }
    }
    out
}

fn read1(store: &ParamStore, number: u16) -> i32 {
    ParamNumber::new(i64::from(number))
        .ok()
        .and_then(|n| store.read(n, None, None).ok())
        .unwrap_or(0)
}

/// Power-on (and Identity Reset): the addressing parameters are read in (BU 0620 §4.2.2,
/// BU 2100 §7.1.2: "After setting, restart … so that the parameter setting is read in").
/// In fixed mode (0) the present address is P850/P160 with its mask; with BOOTP or DHCP it is
/// the address the adapter is reached at.
pub(super) fn power_on(a: &mut Adapter) {
    let p = ip_params(a.product());
    let mac = mac(a);
    let served = *a.address.ip();
    let Ok(store) = a.device.store(Unit::Interface) else {
        return;
    };
    let (ip, mask) = if read1(store, p.mode) == 0 {
        (read4(store, p.address), read4(store, p.mask))
    } else {
        (served.octets(), [255, 255, 255, 0])
    };
    for i in 0..4u8 {
        store.set_info(p.present_address, i + 1, i32::from(ip[usize::from(i)]));
        store.set_info(p.present_mask, i + 1, i32::from(mask[usize::from(i)]));
    }
    for (i, b) in mac.iter().enumerate() {
        store.set_info(p.mac, i as u8 + 1, i32::from(*b));
    }
    let gateway = read4(store, p.gateway);
    for e in 1..=2 {
        store.set_info(p.active_assembly, e, 0);
    }
    a.gateway = gateway;
}

/// Shows the active assemblies (P879 / P180: [-01] consumed, [-02] produced).
pub(super) fn show_active_assembly(a: &mut Adapter, consumed: u16, produced: u16) {
    let p = ip_params(a.product());
    if let Ok(store) = a.device.store(Unit::Interface) {
        store.set_info(p.active_assembly, 1, i32::from(consumed));
        store.set_info(p.active_assembly, 2, i32::from(produced));
    }
}

/// Answers one message-router request.
pub(super) fn request(
    a: &mut Adapter,
    client: ClientId,
    peer: SocketAddr,
    bytes: &[u8],
    now: Duration,
) -> MrResponse {
    let req = match MrRequest::parse(bytes) {
        Ok(r) => r,
        Err(e) => {
            let service = bytes.first().copied().unwrap_or(0) & 0x7F;
            let status = match e {
                _ if bytes.len() < 2 => GS::NOT_ENOUGH_DATA,
                Error::Length { .. } | Error::Truncated { .. } => GS::PATH_SIZE_INVALID,
                _ => GS::PATH_SEGMENT_ERROR,
            };
            return malformed(service, status);
        }
    };
    // What an earlier parameter write set in motion shows before this request (P150 → P175,
    // P152's factory settings): the device's monitoring runs.
    a.device.tick(now);
    let s = req.service;
    match req.path.class_id() {
        Some(class::IDENTITY) => identity(a, &req),
        Some(class::MESSAGE_ROUTER) => message_router(&req),
        Some(class::ASSEMBLY) => connections::assembly_service(a, &req, now),
        Some(class::CONNECTION_MANAGER) => match Service(s) {
            Service::FORWARD_OPEN | Service::LARGE_FORWARD_OPEN => {
                connections::forward_open(a, client, peer, &req, now)
            }
            Service::FORWARD_CLOSE => connections::forward_close(a, &req),
            Service::UNCONNECTED_SEND => unconnected_send(a, client, peer, &req, now),
            _ => MrResponse::error(s, GS::SERVICE_NOT_SUPPORTED),
        },
        Some(class::TCP_IP) => tcp_ip(a, &req),
        Some(class::ETHERNET_LINK) => ethernet_link(a, &req),
        Some(class::DLR) => dlr(&req),
        Some(c @ 100..=108) => parameter(a, c, &req),
        _ => MrResponse::error(s, GS::PATH_DESTINATION_UNKNOWN),
    }
}

/// Unconnected_Send addressed to this device: the embedded request is answered directly.
fn unconnected_send(
    a: &mut Adapter,
    client: ClientId,
    peer: SocketAddr,
    req: &MrRequest,
    now: Duration,
) -> MrResponse {
    let us = match UnconnectedSend::parse(&req.data) {
        Ok(u) => u,
        Err(Error::Truncated { .. }) => return MrResponse::error(req.service, GS::NOT_ENOUGH_DATA),
        Err(_) => {
            return MrResponse {
                service: req.service,
                general: GS::CONNECTION_FAILURE.0,
                extended: vec![proto::enip::cm::ext::UNCONNECTED_SEND_PARAMETER],
                data: Vec::new(),
            }
        }
    };
    // The route ends here: a single port segment (backplane, slot 0) or none.
    let local = us.route.segments.is_empty()
        || matches!(us.route.segments.as_slice(), [Segment::Port { port: 1, link }] if link == &[0]);
    if !local {
        return MrResponse {
            service: req.service,
            general: GS::CONNECTION_FAILURE.0,
            extended: vec![proto::enip::cm::ext::PORT_NOT_AVAILABLE],
            data: Vec::new(),
        };
    }
    request(a, client, peer, &us.request, now)
}

fn instance_one(req: &MrRequest) -> bool {
    req.path.instance_id() == Some(1)
}

fn get_single(req: &MrRequest, value: impl Fn(u16) -> Option<Vec<u8>>) -> MrResponse {
    match req.path.attribute_id() {
        Some(attr) => match value(attr) {
            Some(v) => MrResponse::ok(req.service, v),
            None => MrResponse::error(req.service, GS::ATTRIBUTE_NOT_SUPPORTED),
        },
        None => MrResponse::error(req.service, GS::PATH_SEGMENT_ERROR),
    }
}

/// Class-level attribute 1 (revision) of every object, instance 0.
fn class_attribute(req: &MrRequest, revision: u16) -> Option<MrResponse> {
    (req.path.instance_id() == Some(0) && Service(req.service) == Service::GET_ATTRIBUTE_SINGLE)
        .then(|| {
            get_single(req, |attr| {
                (attr == 1).then(|| revision.to_le_bytes().to_vec())
            })
        })
}

fn identity(a: &mut Adapter, req: &MrRequest) -> MrResponse {
    if let Some(r) = class_attribute(req, 1) {
        return r;
    }
    if !instance_one(req) {
        return MrResponse::error(req.service, GS::PATH_DESTINATION_UNKNOWN);
    }
    match Service(req.service) {
        Service::GET_ATTRIBUTES_ALL => MrResponse::ok(req.service, a.identity.all()),
        Service::GET_ATTRIBUTE_SINGLE => {
            let id = a.identity.clone();
            get_single(req, |attr| id.attribute(attr))
        }
        Service::SET_ATTRIBUTE_SINGLE => match req.path.attribute_id() {
            Some(attr) if a.identity.attribute(attr).is_some() => {
                MrResponse::error(req.service, GS::ATTRIBUTE_NOT_SETTABLE)
            }
            _ => MrResponse::error(req.service, GS::ATTRIBUTE_NOT_SUPPORTED),
        },
        Service::RESET => match req.data.as_slice() {
            [] | [0] => {
                // Type 0: emulate a power cycle of the interface — connections end and the
                // addressing parameters are read in.
                connections::close_all(a);
                power_on(a);
                MrResponse::ok(req.service, Vec::new())
            }
            [_] => MrResponse::error(req.service, GS::INVALID_PARAMETER),
            _ => MrResponse::error(req.service, GS::TOO_MUCH_DATA),
        },
        _ => MrResponse::error(req.service, GS::SERVICE_NOT_SUPPORTED),
    }
}

/// The object classes the message router knows (attribute 1 of instance 1).
const OBJECTS: [u16; 7] = [
    class::IDENTITY,
    class::MESSAGE_ROUTER,
    class::ASSEMBLY,
    class::CONNECTION_MANAGER,
    class::DLR,
    class::TCP_IP,
    class::ETHERNET_LINK,
];

fn message_router(req: &MrRequest) -> MrResponse {
    if let Some(r) = class_attribute(req, 1) {
        return r;
    }
    if !instance_one(req) {
        return MrResponse::error(req.service, GS::PATH_DESTINATION_UNKNOWN);
    }
    match Service(req.service) {
        Service::GET_ATTRIBUTE_SINGLE => get_single(req, |attr| {
            (attr == 1).then(|| {
                let mut v = (OBJECTS.len() as u16).to_le_bytes().to_vec();
                for c in OBJECTS {
                    v.extend(c.to_le_bytes());
                }
                v
            })
        }),
        _ => MrResponse::error(req.service, GS::SERVICE_NOT_SUPPORTED),
    }
}

fn ipv4(b: [u8; 4]) -> Vec<u8> {
    // CIP UDINT of an address: little-endian of the address as a number.
    u32::from(Ipv4Addr::from(b)).to_le_bytes().to_vec()
}

/// TCP/IP Interface object (F5h), instance 1, backed by the addressing parameters.
fn tcp_ip(a: &mut Adapter, req: &MrRequest) -> MrResponse {
    if let Some(r) = class_attribute(req, 4) {
        return r;
    }
    if !instance_one(req) {
        return MrResponse::error(req.service, GS::PATH_DESTINATION_UNKNOWN);
    }
    let p = ip_params(a.product());
    let inactivity_timeout = a.inactivity_timeout;
    let gateway = a.gateway;
    if Service(req.service) == Service::SET_ATTRIBUTE_SINGLE && req.path.attribute_id() == Some(13)
    {
        return set_inactivity_timeout(a, req);
    }
    let Ok(store) = a.device.store(Unit::Interface) else {
        return MrResponse::error(req.service, GS::DEVICE_STATE_CONFLICT);
    };
    match Service(req.service) {
        Service::GET_ATTRIBUTE_SINGLE => get_single(req, |attr| {
            Some(match attr {
                // Status: interface configuration valid.
                1 => 1u32.to_le_bytes().to_vec(),
                // Capability: BOOTP client, DHCP client, configuration settable.
                2 => 0x15u32.to_le_bytes().to_vec(),
                // Configuration control: 0 static, 1 BOOTP, 2 DHCP (= P856 / P165).
                3 => (read1(store, p.mode) as u32).to_le_bytes().to_vec(),
                // Physical link object: path to Ethernet Link instance 1.
                4 => vec![2, 0, 0x20, 0xF6, 0x24, 0x01],
                5 => {
                    let mut v = ipv4(read4(store, p.present_address));
                    v.extend(ipv4(read4(store, p.present_mask)));
                    v.extend(ipv4(gateway));
                    v.extend([0; 8]);
                    v.extend([0, 0]);
                    v
                }
                6 => vec![0, 0],
                // Encapsulation Inactivity Timeout, seconds.
                13 => inactivity_timeout.to_le_bytes().to_vec(),
                _ => return None,
            })
        }),
        Service::SET_ATTRIBUTE_SINGLE => match req.path.attribute_id() {
            Some(3) => {
                let [mode, 0, 0, 0] = req.data.as_slice() else {
                    return MrResponse::error(
                        req.service,
                        if req.data.len() < 4 {
                            GS::NOT_ENOUGH_DATA
                        } else if req.data.len() > 4 {
                            GS::TOO_MUCH_DATA
                        } else {
                            GS::INVALID_ATTRIBUTE_VALUE
                        },
                    );
                };
                let Ok(n) = ParamNumber::new(i64::from(p.mode)) else {
                    return MrResponse::error(req.service, GS::DEVICE_STATE_CONFLICT);
                };
                match store.write(n, None, None, i32::from(*mode), Persist::Eeprom) {
                    Ok(()) => MrResponse::ok(req.service, Vec::new()),
                    Err(_) => MrResponse::error(req.service, GS::INVALID_ATTRIBUTE_VALUE),
                }
            }
            Some(1 | 2 | 4 | 5 | 6) => MrResponse::error(req.service, GS::ATTRIBUTE_NOT_SETTABLE),
            _ => MrResponse::error(req.service, GS::ATTRIBUTE_NOT_SUPPORTED),
        },
        _ => MrResponse::error(req.service, GS::SERVICE_NOT_SUPPORTED),
    }
}

/// Set_Attribute_Single of TCP/IP attribute 13, a UINT of 0 (disabled) to 3600 seconds;
/// beyond is "invalid attribute value" (09h), as OpENer answers.
fn set_inactivity_timeout(a: &mut Adapter, req: &MrRequest) -> MrResponse {
    let value = match req.data[..] {
        [lo, hi] => u16::from_le_bytes([lo, hi]),
        [] | [_] => return MrResponse::error(req.service, GS::NOT_ENOUGH_DATA),
        _ => return MrResponse::error(req.service, GS::TOO_MUCH_DATA),
    };
    if value > super::MAX_INACTIVITY_TIMEOUT {
        return MrResponse::error(req.service, GS::INVALID_ATTRIBUTE_VALUE);
    }
    a.inactivity_timeout = value;
    MrResponse::ok(req.service, Vec::new())
}

/// Ethernet Link object (F6h), instance 1.
fn ethernet_link(a: &mut Adapter, req: &MrRequest) -> MrResponse {
    if let Some(r) = class_attribute(req, 4) {
        return r;
    }
    if !instance_one(req) {
        return MrResponse::error(req.service, GS::PATH_DESTINATION_UNKNOWN);
    }
    let mac = mac(a);
    match Service(req.service) {
        Service::GET_ATTRIBUTE_SINGLE => get_single(req, |attr| {
            Some(match attr {
                // 100 Mbit/s (BU 0620 §2.3.1 "Transfer rate 100 MBit").
                1 => 100u32.to_le_bytes().to_vec(),
                // Link active, full duplex, negotiation succeeded.
                2 => 0x0Du32.to_le_bytes().to_vec(),
                3 => mac.to_vec(),
                _ => return None,
            })
        }),
        Service::SET_ATTRIBUTE_SINGLE => MrResponse::error(req.service, GS::ATTRIBUTE_NOT_SETTABLE),
        _ => MrResponse::error(req.service, GS::SERVICE_NOT_SUPPORTED),
    }
}

/// DLR object class revision: 3 (the attributes a revision-4 object adds are optional for a
/// ring node and not kept).
const DLR_REVISION: u16 = 3;
/// DLR capability flags (attribute 12): beacon-based ring node (bit 1) that handles the
/// Flush_Tables frame (bit 7), as a revision-3 ring node must; not supervisor-capable (bit 5),
/// no redundant gateway (bit 6).
const DLR_CAPABILITIES: u32 = 0x02 | 0x80;

/// The Device Level Ring object (class 47h): BU 0620 §2.3.1 "Supported functions UCMM, DLR",
/// §2.3.2 ring topology without an external switch (BU 2100 §2.1 the same). The device is a
/// ring node, not a ring supervisor, so instance 1 has the attributes CIP Vol 2 requires of a
/// non-supervisor node: 1 network topology, 2 network status, 10 active supervisor address,
/// 12 capability flags; the supervisor's (3–9, 11) and a redundant gateway's (13–16) are
/// absent. The simulator sits on one link, not in a ring: topology 0 (linear), status 0
/// (normal), no active supervisor (address 0.0.0.0, MAC 00-00-00-00-00-00).
fn dlr(req: &MrRequest) -> MrResponse {
    if let Some(r) = class_attribute(req, DLR_REVISION) {
        return r;
    }
    if !instance_one(req) {
        return MrResponse::error(req.service, GS::PATH_DESTINATION_UNKNOWN);
    }
    let attribute = |attr: u16| -> Option<Vec<u8>> {
        Some(match attr {
            1 => vec![0],
            2 => vec![0],
            10 => vec![0; 10],
            12 => DLR_CAPABILITIES.to_le_bytes().to_vec(),
            _ => return None,
        })
    };
    match Service(req.service) {
        Service::GET_ATTRIBUTE_SINGLE => get_single(req, attribute),
        Service::GET_ATTRIBUTES_ALL => {
            let mut v = Vec::new();
            for attr in [1, 2, 10, 12] {
                v.extend(attribute(attr).unwrap_or_default());
            }
            MrResponse::ok(req.service, v)
        }
        _ => MrResponse::error(req.service, GS::SERVICE_NOT_SUPPORTED),
    }
}

/// The unit behind a parameter class: 100 the module itself, 101..108 FI 1..8. The SK 550P's
/// interface is built into FI 1, so its P85x–P89x answer in class 101 (BU 0620 §2.3.5 lists
/// classes 101–108 only).
fn unit_of(a: &mut Adapter, class: u16, number: ParamNumber) -> Option<Unit> {
    let product = a.product();
    match (product.family(), class) {
        (Family::Module, 100) => Some(Unit::Interface),
        (Family::Integrated, 100) => None,
        (_, c) => {
            let fi = Inverter::new(i64::from(c - 100)).ok()?;
            if product.family() == Family::Integrated && fi.get() == 1 {
                let iface = a.device.store(Unit::Interface).ok()?;
                if iface.def(number).is_some() {
                    return Some(Unit::Interface);
                }
            }
            a.device.store(Unit::Inverter(fi)).ok()?;
            Some(Unit::Inverter(fi))
        }
    }
}

/// Get/Set_Attribute_Single on a parameter: class 100 + FI, instance from set and element,
/// attribute = parameter number; values are INT (16 bit) or DINT (positions), little-endian.
fn parameter(a: &mut Adapter, class: u16, req: &MrRequest) -> MrResponse {
    let s = req.service;
    let (Some(instance), Some(attr)) = (req.path.instance_id(), req.path.attribute_id()) else {
        return MrResponse::error(s, GS::PATH_DESTINATION_UNKNOWN);
    };
    let get = Service(s) == Service::GET_ATTRIBUTE_SINGLE;
    if !get && Service(s) != Service::SET_ATTRIBUTE_SINGLE {
        return MrResponse::error(s, GS::SERVICE_NOT_SUPPORTED);
    }
    let Ok(number) = ParamNumber::new(i64::from(attr)) else {
        return MrResponse::error(s, GS::ATTRIBUTE_NOT_SUPPORTED);
    };
    let Some(unit) = unit_of(a, class, number) else {
        return MrResponse::error(s, GS::PATH_DESTINATION_UNKNOWN);
    };
    let product = a.product();
    let Ok(store) = a.device.store(unit) else {
        return MrResponse::error(s, GS::PATH_DESTINATION_UNKNOWN);
    };
    let Some(def) = store.def(number) else {
        return MrResponse::error(s, GS::ATTRIBUTE_NOT_SUPPORTED);
    };
    let Some((set, element)) = cip_decode_instance(instance, def.set_dependent, def.array) else {
        return MrResponse::error(s, GS::PATH_DESTINATION_UNKNOWN);
    };
    let width = match def.width {
        Width::Word => 2,
        Width::Dword => 4,
    };
    // The instance's set and element as the parameter object's sub-index: behind a bus
    // module (and the SK 550P's FI 2…8) the gateway reads and writes it on the inverter's
    // node over the system bus.
    let sub = proto::nord::addr::sdo_subindex(set, element);
    if get {
        if !req.data.is_empty() {
            return MrResponse::error(s, GS::TOO_MUCH_DATA);
        }
        return match a.device.gateway_read(unit, number, sub) {
            Ok(bytes) => MrResponse::ok(s, bytes),
            Err(r) => MrResponse::error(s, refusal_status(r)),
        };
    }
    // BU 0620 §4.2.2 P853: "Writing only possible via USS or USB".
    if product == Product::Sk550p && attr == 853 {
        return MrResponse::error(s, GS::ATTRIBUTE_NOT_SETTABLE);
    }
    if def.access == ParamAccess::ReadOnly {
        return MrResponse::error(s, GS::ATTRIBUTE_NOT_SETTABLE);
    }
    match req.data.len() {
        n if n < width => return MrResponse::error(s, GS::NOT_ENOUGH_DATA),
        n if n > width => return MrResponse::error(s, GS::TOO_MUCH_DATA),
        _ => {}
    }
    // The INT or DINT as it came, little-endian: the parameter object's INTEGER16 (UNSIGNED16
    // for a range above 7FFFh) or INTEGER32 (`proto::nord::ecat::parameter_data_type`).
    match a.device.gateway_write(unit, number, sub, &req.data) {
        Ok(()) => MrResponse::ok(s, Vec::new()),
        Err(r) => MrResponse::error(s, refusal_status(r)),
    }
}

/// The CIP general status of a parameter access refused on the inverter's node or store: the
/// store's own reason where it refused ([`access_status`]), else the abort code's
/// ([`abort_status`]). Both give one status for a store's refusal: the reason is finer than
/// the code, the status coarser than either.
fn refusal_status(r: Refused) -> GS {
    r.cause.map_or_else(|| abort_status(r.abort), access_status)
}

/// The CIP general status of an SDO abort code from the system bus: the status
/// [`access_status`] gives the store's refusal that the node answers with that code
/// (`crate::objects::abort_of`), the data length's codes as CIP's own length statuses, and
/// a transfer that failed (time-out, protocol, an inverter not reached) "device state
/// conflict".
fn abort_status(code: SdoAbort) -> GS {
    match code {
        abort::NO_OBJECT => GS::ATTRIBUTE_NOT_SUPPORTED,
        abort::READ_ONLY => GS::ATTRIBUTE_NOT_SETTABLE,
        abort::VALUE_RANGE | abort::VALUE_TOO_HIGH | abort::VALUE_TOO_LOW => {
            GS::INVALID_ATTRIBUTE_VALUE
        }
        abort::NO_SUBINDEX => GS::PATH_DESTINATION_UNKNOWN,
        abort::TOO_LONG => GS::TOO_MUCH_DATA,
        abort::TOO_SHORT => GS::NOT_ENOUGH_DATA,
        _ => GS::DEVICE_STATE_CONFLICT,
    }
}

/// The CIP general status of a refused parameter access.
pub(crate) fn access_status(e: AccessError) -> GS {
    match e {
        AccessError::NoSuchParameter => GS::ATTRIBUTE_NOT_SUPPORTED,
        AccessError::ReadOnly => GS::ATTRIBUTE_NOT_SETTABLE,
        AccessError::OutOfRange | AccessError::OnlyResettable => GS::INVALID_ATTRIBUTE_VALUE,
        AccessError::BadSubIndex | AccessError::NotAnArray => GS::PATH_DESTINATION_UNKNOWN,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::objects::abort_of;

    /// Every refusal a parameter store gives today has one CIP status, whether the gateway
    /// answers from the store's reason or from the node's abort code alone.
    #[test]
    fn a_stores_refusal_gives_one_status_through_its_abort_code() {
        let errors = AccessError::ALL;
        for def in proto::nord::params::CATALOGUE.iter() {
            for e in errors {
                for value in [
                    def.min.saturating_sub(1),
                    def.min,
                    def.max,
                    def.max.saturating_add(1),
                ] {
                    let code = abort_of(e, value, Some(def));
                    assert_eq!(abort_status(code), access_status(e), "{e:?} as {code:?}");
                    let r = Refused {
                        abort: code,
                        cause: Some(e),
                    };
                    assert_eq!(refusal_status(r), access_status(e));
                }
            }
        }
        // Refusals of the object layout or the transfer, no store's reason beside them.
        assert_eq!(abort_status(abort::TOO_SHORT), GS::NOT_ENOUGH_DATA);
        assert_eq!(abort_status(abort::TIMEOUT), GS::DEVICE_STATE_CONFLICT);
    }

    /// A CIP instance's set and element, as the parameter object's sub-index the gateway
    /// sends, name the same value again on the node; and a CIP INT the node reads as its
    /// INTEGER16 or UNSIGNED16 is the same value wherever the parameter's range has it (CIP
    /// takes an INT as signed where the range is, the node where its type is).
    #[test]
    fn the_gateways_sub_index_and_data_name_what_the_cip_instance_and_value_do() {
        use proto::nord::addr::{cip_instance, sdo_subindex};
        use proto::nord::ecat::{parameter_data_type, parameter_subindex, DataType, ParamSub};
        use proto::nord::{ArrayElement, ParamSet};
        for def in proto::nord::params::CATALOGUE.iter() {
            let sets: Vec<Option<ParamSet>> = match def.set_dependent {
                true => (1..=4).map(|s| ParamSet::new(s).ok()).collect(),
                false => vec![None],
            };
            let elements: Vec<Option<ArrayElement>> = match def.array {
                Some(n) => (1..=i64::from(n))
                    .map(|e| ArrayElement::new(e).ok())
                    .collect(),
                None => vec![None],
            };
            for &set in &sets {
                for &element in &elements {
                    let instance = u32::from(cip_instance(set, element));
                    let decoded = cip_decode_instance(instance, def.set_dependent, def.array);
                    assert_eq!(decoded, Some((set, element)), "P{}", def.number);
                    let sub = sdo_subindex(set, element);
                    assert_eq!(
                        parameter_subindex(sub, def.set_dependent, def.array),
                        Some(ParamSub::Value(set, element)),
                        "P{} sub {sub}",
                        def.number
                    );
                }
            }
            if def.width == Width::Word {
                let node_signed = parameter_data_type(def) == DataType::I16;
                let cip_signed = def.min < 0;
                // Where they differ, only values outside the range read differently.
                if node_signed != cip_signed {
                    assert!(
                        def.min >= 0 && def.max <= i32::from(i16::MAX),
                        "P{} {}..{}",
                        def.number,
                        def.min,
                        def.max
                    );
                }
            }
        }
    }
}
