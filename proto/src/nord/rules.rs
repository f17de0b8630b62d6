//! Configuration rules the manuals state: PROFINET device names, POWERLINK IP addresses and
//! gateways, EtherNet/IP addressing modes.
//!
//! BU 0620 §3.8.1 (p. 71) and P854 (§4.2.4, p. 83) give the same conventions with different
//! maximum lengths: 127 characters in §3.8.1, 240 in P854. PROFINET (IEC 61158-6-10, DNS rules)
//! allows 240 characters, in labels of at most 63; the harness takes 240 and records 127 as an
//! erratum (suites/bu0620/rules-device-name.yaml).

/// Longest device name (P854; §3.8.1 prints 127).
pub const DEVICE_NAME_MAX: usize = 240;
/// Longest label between two dots or hyphens.
pub const LABEL_MAX: usize = 63;

/// Why a device name is refused, one variant per rule.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum NameError {
    /// Empty.
    #[error("the device name is empty")]
    Empty,
    /// Over 240 characters.
    #[error("the device name has {0} characters, at most 240 are allowed")]
    TooLong(usize),
    /// A label over 63 characters.
    #[error("`{0}` is longer than 63 characters between two hyphens or full stops")]
    LabelTooLong(String),
    /// A character other than a–z, 0–9, '-', '.'.
    #[error("`{0}` is not allowed (only a…z, 0…9, '-' and '.')")]
    BadCharacter(char),
    /// Starts or ends with a hyphen.
    #[error("the device name must not begin or end with a hyphen")]
    HyphenAtEnd,
    /// Starts or ends with a digit.
    #[error("the device name must not begin or end with a number")]
    DigitAtEnd,
    /// Looks like an IP address.
    #[error("the device name must not have the format n.n.n.n")]
    IpFormat,
    /// Starts with port-nnn.
    #[error("the device name must not start with port-nnn")]
    PortPrefix,
}

/// Checks a PROFINET device name against every rule of §3.8.1 / P854.
pub fn validate_device_name(name: &str) -> Result<(), NameError> {
    if name.is_empty() {
        return Err(NameError::Empty);
    }
    let count = name.chars().count();
    if count > DEVICE_NAME_MAX {
        return Err(NameError::TooLong(count));
    }
    if let Some(c) = name
        .chars()
        .find(|c| !(c.is_ascii_lowercase() || c.is_ascii_digit() || *c == '-' || *c == '.'))
    {
        return Err(NameError::BadCharacter(c));
    }
    if let Some(l) = name.split(['.', '-']).find(|l| l.len() > LABEL_MAX) {
        return Err(NameError::LabelTooLong(l.to_string()));
    }
    if name.starts_with('-') || name.ends_with('-') {
        return Err(NameError::HyphenAtEnd);
    }
    let digit = |c: Option<char>| c.is_some_and(|c| c.is_ascii_digit());
    if digit(name.chars().next()) || digit(name.chars().last()) {
        return Err(NameError::DigitAtEnd);
    }
    let parts: Vec<&str> = name.split('.').collect();
    if parts.len() == 4
        && parts
            .iter()
            .all(|p| !p.is_empty() && p.chars().all(|c| c.is_ascii_digit()))
    {
        return Err(NameError::IpFormat);
    }
    if let Some(rest) = name.strip_prefix("port-") {
        if rest.len() >= 3 && rest.chars().take(3).all(|c| c.is_ascii_digit()) {
            return Err(NameError::PortPrefix);
        }
    }
    Ok(())
}

/// A POWERLINK address setting the manuals forbid.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PlAddressError {
    /// Node id outside 1..239 (BU 0620 §2.4.3.1: controlled nodes).
    #[error("node id {0} is not a controlled-node address (1…239)")]
    NodeId(u8),
    /// Gateway outside 192.168.100.1…240 (BU 0620 §3.7.3, P852): the inverter reports
    /// "5605 set config.".
    #[error(
        "gateway {0}.{1}.{2}.{3} is outside 192.168.100.1…192.168.100.240: error 5605 set config."
    )]
    Gateway(u8, u8, u8, u8),
}

/// The IP address and sub-net mask POWERLINK prescribes for a node id (BU 0620 §3.7.3):
/// 192.168.100.<node id>, 255.255.255.0.
pub fn powerlink_ip(node_id: u8) -> Result<([u8; 4], [u8; 4]), PlAddressError> {
    if !(1..=239).contains(&node_id) {
        return Err(PlAddressError::NodeId(node_id));
    }
    Ok(([192, 168, 100, node_id], [255, 255, 255, 0]))
}

/// Checks a POWERLINK gateway address (BU 0620 §3.7.3 and P852, §4.2.3).
pub fn powerlink_gateway(ip: [u8; 4]) -> Result<(), PlAddressError> {
    match ip {
        [192, 168, 100, 1..=240] => Ok(()),
        [a, b, c, d] => Err(PlAddressError::Gateway(a, b, c, d)),
    }
}

/// Whether the CAN termination resistor (the CAN DIP switch of an inverter, the DIP switch of an
/// absolute encoder) of the device at `position` (1 = first) on a system-bus line of `count`
/// devices is switched on: a CAN line (ISO 11898-2) is terminated with 120 Ω at both of its
/// ends and nowhere between. BU 0620 §3.9 step 1 (p. 73, English edition): ON on FI 1 and FI 3,
/// OFF on FI 2 of a line of three; the Chinese edition prints ON for FI 2 as well (an erratum).
/// `None` where `position` is not on the line (0 or beyond `count`).
pub fn can_termination(position: u8, count: u8) -> Option<bool> {
    if position == 0 || position > count {
        return None;
    }
    Some(position == 1 || position == count)
}

/// Where an EtherNet/IP interface takes its IP configuration from (P856 on the SK 550P, P165 on
/// the modules; BU 0620 §4.2.2, BU 2100 §7.1.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum AddressingMode {
    /// 0: from the IP parameters (P850–P852 / P160, P161, P164).
    Fixed,
    /// 1 (factory setting): BOOTP.
    Bootp,
    /// 2: DHCP.
    Dhcp,
}

impl AddressingMode {
    /// The mode of a parameter value, `None` outside 0…2.
    pub fn from_value(v: i64) -> Option<AddressingMode> {
        match v {
            0 => Some(AddressingMode::Fixed),
            1 => Some(AddressingMode::Bootp),
            2 => Some(AddressingMode::Dhcp),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    #[rstest]
    #[case("sk550p-conveyor.line-a", Ok(()))]
    #[case("", Err(NameError::Empty))]
    #[case("Drive", Err(NameError::BadCharacter('D')))]
    #[case("drive_1a", Err(NameError::BadCharacter('_')))]
    #[case("-drive", Err(NameError::HyphenAtEnd))]
    #[case("1drive", Err(NameError::DigitAtEnd))]
    #[case("drive1", Err(NameError::DigitAtEnd))]
    #[case("port-123x", Err(NameError::PortPrefix))]
    fn names(#[case] name: &str, #[case] want: Result<(), NameError>) {
        assert_eq!(validate_device_name(name), want);
    }

    #[test]
    fn powerlink_addresses() {
        assert_eq!(
            powerlink_ip(5),
            Ok(([192, 168, 100, 5], [255, 255, 255, 0]))
        );
        assert_eq!(powerlink_ip(240), Err(PlAddressError::NodeId(240)));
        assert_eq!(powerlink_gateway([192, 168, 100, 240]), Ok(()));
        assert!(powerlink_gateway([192, 168, 100, 241])
            .unwrap_err()
            .to_string()
            .contains("5605"));
        assert_eq!(AddressingMode::from_value(1), Some(AddressingMode::Bootp));
        assert_eq!(AddressingMode::from_value(3), None);
    }

    #[test]
    fn can_termination_at_both_ends_only() {
        // §3.9 step 1: FI 1 and FI 3 ON, FI 2 OFF.
        assert_eq!(can_termination(1, 3), Some(true));
        assert_eq!(can_termination(2, 3), Some(false));
        assert_eq!(can_termination(3, 3), Some(true));
        assert_eq!(can_termination(1, 1), Some(true));
        assert_eq!(can_termination(0, 3), None);
        assert_eq!(can_termination(4, 3), None);
    }

    #[test]
    fn lengths() {
        let label = "a".repeat(63);
        let ok = [label.as_str(); 3].join(".");
        assert_eq!(validate_device_name(&ok), Ok(()));
        assert!(matches!(
            validate_device_name(&"a".repeat(64)),
            Err(NameError::LabelTooLong(_))
        ));
        let sixty = "a".repeat(60);
        let long = [sixty.as_str(); 4].join(".");
        assert_eq!(long.len(), 243);
        assert_eq!(validate_device_name(&long), Err(NameError::TooLong(243)));
        // 127 < n ≤ 240 is allowed (§3.8.1 prints 127: erratum).
        assert_eq!(validate_device_name(&[sixty.as_str(); 3].join(".")), Ok(()));
    }
}
