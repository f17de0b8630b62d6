//! Name of station and IP suite: the manuals' length statements and conventions (BU 0620
//! §3.8.1, §4.2.4; BU 0590 §5.1.2), the PROFINET rules a DCP Set is checked against (IEC
//! 61158-6-10), the factory IP suites and the mask correction the manuals describe.

use std::net::Ipv4Addr;

use serde::Serialize;

use super::device_id;
use crate::nord::product::Product;
use crate::nord::rules;

/// Longest name of station (IEC 61158-6-10; BU 0620 P854 and BU 0590 P162: 240).
pub const STATION_NAME_MAX: usize = rules::DEVICE_NAME_MAX;

/// Where a manual states a device-name length.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum NameStatement {
    /// BU 0620 §3.8.1 (p. 72), both editions: "a maximum of 127 characters" (erratum).
    Bu0620Setup,
    /// BU 0620 §4.2.4 P854 (p. 83), both editions: 240.
    Bu0620P854,
    /// BU 0590 §5.1.2 P162 (p. 35): "up to 240 characters".
    Bu0590P162,
}

/// The maximum the statement prints.
pub fn printed_name_max(statement: NameStatement) -> usize {
    match statement {
        NameStatement::Bu0620Setup => 127,
        NameStatement::Bu0620P854 | NameStatement::Bu0590P162 => 240,
    }
}

/// The parameter holding the device name: P854 (SK 550P), P162 (SK TU3-PNT).
pub fn name_parameter(product: Product) -> Option<u16> {
    match product {
        Product::Sk550p => Some(854),
        Product::Tu3Pnt => Some(162),
        _ => None,
    }
}

/// The manuals' naming conventions (BU 0620 §3.8.1 / P854, BU 0590 P162): see
/// [`rules::validate_device_name`], which holds them.
pub fn check_manual_name(name: &str) -> Result<(), rules::NameError> {
    rules::validate_device_name(name)
}

/// Why a name of station is refused by the PROFINET rules (IEC 61158-6-10 NameOfStation,
/// PROFINET 2.4 §4.3.1.4.16.2). They are looser than the manuals' conventions: a label may
/// start or end with a digit, a hyphen does not end a label, and only "port-xyz" and
/// "port-xyz-abcde" (digits) are reserved.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum StationNameError {
    /// Over 240 characters.
    #[error("name of station has {0} characters, at most 240 are allowed")]
    TooLong(usize),
    /// A character other than a–z, 0–9, '-', '.'.
    #[error("`{0}` is not allowed in a name of station")]
    BadCharacter(char),
    /// Two dots in a row, or a dot at either end.
    #[error("a label of the name of station is empty")]
    EmptyLabel,
    /// A label over 63 characters.
    #[error("a label has {0} characters, at most 63 are allowed")]
    LabelTooLong(usize),
    /// A label starting or ending with '-'.
    #[error("a label must not begin or end with a hyphen")]
    HyphenAtLabelEnd,
    /// "port-xyz" or "port-xyz-abcde".
    #[error("the first label must not be port-xyz or port-xyz-abcde")]
    PortName,
    /// a.b.c.d with digits only.
    #[error("the name of station must not have the form n.n.n.n")]
    IpFormat,
}

/// Checks a name of station as a DCP Set carries it. The empty name is valid ("no name").
pub fn check_station_name(name: &str) -> Result<(), StationNameError> {
    let count = name.chars().count();
    if count > STATION_NAME_MAX {
        return Err(StationNameError::TooLong(count));
    }
    if name.is_empty() {
        return Ok(());
    }
    if let Some(c) = name
        .chars()
        .find(|c| !(c.is_ascii_lowercase() || c.is_ascii_digit() || matches!(c, '-' | '.')))
    {
        return Err(StationNameError::BadCharacter(c));
    }
    let labels: Vec<&str> = name.split('.').collect();
    for l in &labels {
        if l.is_empty() {
            return Err(StationNameError::EmptyLabel);
        }
        if l.len() > rules::LABEL_MAX {
            return Err(StationNameError::LabelTooLong(l.len()));
        }
        if l.starts_with('-') || l.ends_with('-') {
            return Err(StationNameError::HyphenAtLabelEnd);
        }
    }
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    let first: Vec<&str> = labels[0].split('-').collect();
    if first[0] == "port"
        && ((first.len() == 2 && first[1].len() == 3 && digits(first[1]))
            || (first.len() == 3
                && first[1].len() == 3
                && digits(first[1])
                && first[2].len() == 5
                && digits(first[2])))
    {
        return Err(StationNameError::PortName);
    }
    if labels.len() == 4 && labels.iter().all(|l| digits(l)) {
        return Err(StationNameError::IpFormat);
    }
    Ok(())
}

/// An IP suite: address, sub-net mask, gateway.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct IpSuite {
    /// IP address.
    pub ip: Ipv4Addr,
    /// Sub-net mask.
    pub mask: Ipv4Addr,
    /// Gateway (0.0.0.0: none).
    pub gateway: Ipv4Addr,
}

/// Factory IP suite: BU 0620 §4.2.4 P850/P851/P852 (p. 82: 192.168.20.200, 255.255.255.0,
/// 0.0.0.0 — under EtherNet/IP, §4.2.2, P850's factory setting is 192.168.1.100); BU 0590
/// §5.1.2 P160/P161 (p. 34: the same; the module has no gateway parameter).
pub fn factory_ip(product: Product) -> Option<IpSuite> {
    device_id(product)?;
    Some(IpSuite {
        ip: Ipv4Addr::new(192, 168, 20, 200),
        mask: Ipv4Addr::new(255, 255, 255, 0),
        gateway: Ipv4Addr::UNSPECIFIED,
    })
}

/// The parameters of the IP suite.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct IpParameters {
    /// IP address (4 elements).
    pub ip: u16,
    /// Sub-net mask (4 elements).
    pub mask: u16,
    /// Gateway, where the product has one.
    pub gateway: Option<u16>,
    /// The present address, mask and gateway (display), where the product has them.
    pub present: Option<[u16; 3]>,
}

/// SK 550P: P850, P851, P852, present P875, P876, P877 (BU 0620 §4.2.4, §4.4.3); SK TU3-PNT:
/// P160, P161 (BU 0590 §5.1.2), no gateway or present-address parameters.
pub fn ip_parameters(product: Product) -> Option<IpParameters> {
    match product {
        Product::Sk550p => Some(IpParameters {
            ip: 850,
            mask: 851,
            gateway: Some(852),
            present: Some([875, 876, 877]),
        }),
        Product::Tu3Pnt => Some(IpParameters {
            ip: 160,
            mask: 161,
            gateway: None,
            present: None,
        }),
        _ => None,
    }
}

/// Whether an IP suite set by the IO controller leaves the IP parameters at 0: BU 0620 §4.2.4
/// (P850, P851, P852: "This parameter is then set to '0'"; the address in use shows in
/// P875–P877). BU 0590 says nothing of the kind for P160/P161.
pub fn controller_ip_zeroes_parameters(product: Product) -> bool {
    product == Product::Sk550p
}

/// An IP suite PROFINET refuses (IEC 61158-6-10 IP suite rules, as p-net's CMINA checks them;
/// a DCP Set carrying one is answered with block error 03h "suboption not set").
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum IpSuiteError {
    /// The mask's ones are not contiguous.
    #[error("sub-net mask {0} is not contiguous")]
    Mask(Ipv4Addr),
    /// Host part all zeros or ones, 0/8, loopback, multicast or class E.
    #[error("{0} is not a unicast host address in its sub-net")]
    Address(Ipv4Addr),
    /// A gateway outside the sub-net.
    #[error("gateway {0} is not in the device's sub-net")]
    Gateway(Ipv4Addr),
}

/// Checks an IP suite. 0.0.0.0/0.0.0.0/0.0.0.0 ("no address") is valid.
pub fn check_ip_suite(s: &IpSuite) -> Result<(), IpSuiteError> {
    let (ip, mask, gw) = (u32::from(s.ip), u32::from(s.mask), u32::from(s.gateway));
    if mask & (!mask >> 1) != 0 {
        return Err(IpSuiteError::Mask(s.mask));
    }
    if ip == 0 && mask == 0 {
        return if gw == 0 {
            Ok(())
        } else {
            Err(IpSuiteError::Gateway(s.gateway))
        };
    }
    let host = ip & !mask;
    let first = s.ip.octets()[0];
    if mask == 0 || host == 0 || host == !mask || first == 0 || first == 127 || first >= 224 {
        return Err(IpSuiteError::Address(s.ip));
    }
    if gw != 0 && (gw & mask != ip & mask || gw == ip) {
        return Err(IpSuiteError::Gateway(s.gateway));
    }
    Ok(())
}

/// The classful mask of an address (A 255.0.0.0, B 255.255.0.0, C 255.255.255.0), `None` for
/// classes D and E.
pub fn class_mask(ip: Ipv4Addr) -> Option<Ipv4Addr> {
    match ip.octets()[0] {
        0..=127 => Some(Ipv4Addr::new(255, 0, 0, 0)),
        128..=191 => Some(Ipv4Addr::new(255, 255, 0, 0)),
        192..=223 => Some(Ipv4Addr::new(255, 255, 255, 0)),
        _ => None,
    }
}

/// Whether a mask "conforms with" an address (BU 0590 P161 p. 34: 192.168.20.200 with
/// 255.255.255.0 correct, with 255.0.0.0 an error): contiguous and no shorter than the
/// address's class mask. The manuals give only that example; the classful reading is ours.
pub fn mask_conforms(ip: Ipv4Addr, mask: Ipv4Addr) -> bool {
    let m = u32::from(mask);
    m & (!m >> 1) == 0 && class_mask(ip).is_some_and(|c| m & u32::from(c) == u32::from(c))
}

/// The mask after an address is entered (BU 0620 §3.8.1/P850, BU 0590 P160: "the IP sub-net
/// mask is corrected automatically"): kept where it conforms, else the class mask.
pub fn corrected_mask(ip: Ipv4Addr, mask: Ipv4Addr) -> Ipv4Addr {
    if mask_conforms(ip, mask) {
        mask
    } else {
        class_mask(ip).unwrap_or(mask)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    #[test]
    fn name_lengths_per_manual() {
        assert_eq!(printed_name_max(NameStatement::Bu0620Setup), 127);
        assert_eq!(
            printed_name_max(NameStatement::Bu0620P854),
            STATION_NAME_MAX
        );
        assert_eq!(printed_name_max(NameStatement::Bu0590P162), 240);
        assert_eq!(name_parameter(Product::Tu3Pnt), Some(162));
    }

    #[rstest]
    #[case("sk550p-1.line-a", Ok(()))]
    #[case("", Ok(()))]
    #[case("1drive", Ok(()))] // the standard allows what the manuals' convention forbids
    #[case("drive1", Ok(()))]
    #[case("port-123x", Ok(()))]
    #[case("port-123", Err(StationNameError::PortName))]
    #[case("port-123-45678.plant", Err(StationNameError::PortName))]
    #[case("192.168.0.1", Err(StationNameError::IpFormat))]
    #[case("Drive", Err(StationNameError::BadCharacter('D')))]
    #[case("a..b", Err(StationNameError::EmptyLabel))]
    #[case("a.-b", Err(StationNameError::HyphenAtLabelEnd))]
    fn station_names(#[case] name: &str, #[case] want: Result<(), StationNameError>) {
        assert_eq!(check_station_name(name), want);
    }

    #[test]
    fn station_name_lengths() {
        let label = "a".repeat(63);
        assert_eq!(check_station_name(&label), Ok(()));
        assert_eq!(
            check_station_name(&"a".repeat(64)),
            Err(StationNameError::LabelTooLong(64))
        );
        let long = [&"a".repeat(60)[..]; 4].join(".");
        assert_eq!(
            check_station_name(&long),
            Err(StationNameError::TooLong(243))
        );
        assert_eq!(
            check_manual_name("drive1"),
            Err(rules::NameError::DigitAtEnd)
        );
    }

    #[test]
    fn ip_factory_and_rules() {
        let f = factory_ip(Product::Sk550p).unwrap();
        assert_eq!(f.ip, Ipv4Addr::new(192, 168, 20, 200));
        assert_eq!(factory_ip(Product::Tu3Pnt), Some(f));
        assert_eq!(check_ip_suite(&f), Ok(()));
        assert_eq!(ip_parameters(Product::Tu3Pnt).unwrap().gateway, None);
        assert_eq!(
            ip_parameters(Product::Sk550p).unwrap().present,
            Some([875, 876, 877])
        );
        let ip = |a, b, c, d| Ipv4Addr::new(a, b, c, d);
        let s = |i, m, g| IpSuite {
            ip: i,
            mask: m,
            gateway: g,
        };
        let none = Ipv4Addr::UNSPECIFIED;
        assert_eq!(check_ip_suite(&s(none, none, none)), Ok(()));
        assert!(matches!(
            check_ip_suite(&s(ip(192, 168, 0, 1), ip(255, 0, 255, 0), none)),
            Err(IpSuiteError::Mask(_))
        ));
        assert!(matches!(
            check_ip_suite(&s(ip(192, 168, 0, 255), ip(255, 255, 255, 0), none)),
            Err(IpSuiteError::Address(_))
        ));
        assert!(matches!(
            check_ip_suite(&s(ip(127, 0, 0, 1), ip(255, 0, 0, 0), none)),
            Err(IpSuiteError::Address(_))
        ));
        assert!(matches!(
            check_ip_suite(&s(
                ip(192, 168, 0, 1),
                ip(255, 255, 255, 0),
                ip(10, 0, 0, 1)
            )),
            Err(IpSuiteError::Gateway(_))
        ));
        // BU 0590 P161 p. 34: 255.255.255.0 correct, 255.0.0.0 an error for 192.168.20.200.
        assert!(mask_conforms(f.ip, f.mask));
        assert!(!mask_conforms(f.ip, ip(255, 0, 0, 0)));
        assert_eq!(corrected_mask(f.ip, ip(255, 0, 0, 0)), f.mask);
        assert_eq!(
            corrected_mask(ip(10, 1, 2, 3), ip(255, 255, 0, 0)),
            ip(255, 255, 0, 0)
        );
        assert!(controller_ip_zeroes_parameters(Product::Sk550p));
    }
}
