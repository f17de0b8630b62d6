//! LLDP (IEEE 802.1AB) data units as a PROFINET IO device sends them: conformance class B
//! devices detect the topology with LLDP (BU 0620 §2.5.3, IEC 61158-6-10). A device names its
//! chassis by its name of station and its port by "port-001"; the mandatory TLVs are chassis
//! ID, port ID, time to live and the end TLV.

use crate::eth::MacAddr;

/// The nearest-bridge multicast address LLDP frames go to.
pub const MULTICAST: MacAddr = MacAddr([0x01, 0x80, 0xC2, 0x00, 0x00, 0x0E]);
/// Chassis ID / port ID subtype "locally assigned" (IEEE 802.1AB: 7).
pub const LOCALLY_ASSIGNED: u8 = 7;

const END: u8 = 0;
const CHASSIS_ID: u8 = 1;
const PORT_ID: u8 = 2;
const TTL: u8 = 3;

/// The mandatory content of an LLDPDU.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Lldpdu {
    /// Chassis ID subtype and value.
    pub chassis: (u8, Vec<u8>),
    /// Port ID subtype and value.
    pub port: (u8, Vec<u8>),
    /// Time to live, seconds.
    pub ttl: u16,
}

fn tlv(out: &mut Vec<u8>, kind: u8, value: &[u8]) {
    // 7-bit type, 9-bit length.
    let head = u16::from(kind) << 9 | (value.len() as u16 & 0x01FF);
    out.extend(head.to_be_bytes());
    out.extend(value);
}

impl Lldpdu {
    /// The LLDPDU bytes (the Ethernet payload).
    pub fn emit(&self) -> Vec<u8> {
        let mut out = Vec::new();
        let with_subtype = |(s, v): &(u8, Vec<u8>)| {
            let mut b = vec![*s];
            b.extend(v);
            b
        };
        tlv(&mut out, CHASSIS_ID, &with_subtype(&self.chassis));
        tlv(&mut out, PORT_ID, &with_subtype(&self.port));
        tlv(&mut out, TTL, &self.ttl.to_be_bytes());
        tlv(&mut out, END, &[]);
        out
    }

    /// Reads the mandatory TLVs (others are skipped); `Err` names what is missing or cut.
    pub fn parse(bytes: &[u8]) -> Result<Lldpdu, String> {
        let (mut chassis, mut port, mut ttl) = (None, None, None);
        let mut at = 0;
        while at + 2 <= bytes.len() {
            let head = u16::from_be_bytes([bytes[at], bytes[at + 1]]);
            let (kind, len) = ((head >> 9) as u8, usize::from(head & 0x01FF));
            let value = bytes
                .get(at + 2..at + 2 + len)
                .ok_or_else(|| format!("TLV type {kind} cut at {at}"))?;
            match (kind, value) {
                (END, _) => break,
                (CHASSIS_ID, [s, v @ ..]) => chassis = Some((*s, v.to_vec())),
                (PORT_ID, [s, v @ ..]) => port = Some((*s, v.to_vec())),
                (TTL, [a, b]) => ttl = Some(u16::from_be_bytes([*a, *b])),
                (CHASSIS_ID | PORT_ID | TTL, _) => {
                    return Err(format!("TLV type {kind} malformed"))
                }
                _ => {}
            }
            at += 2 + len;
        }
        Ok(Lldpdu {
            chassis: chassis.ok_or("no chassis ID TLV")?,
            port: port.ok_or("no port ID TLV")?,
            ttl: ttl.ok_or("no time-to-live TLV")?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_refusals() {
        let du = Lldpdu {
            chassis: (LOCALLY_ASSIGNED, b"nord-device".to_vec()),
            port: (LOCALLY_ASSIGNED, b"port-001".to_vec()),
            ttl: 20,
        };
        let b = du.emit();
        // Chassis ID TLV: type 1, length 12 (subtype + 11 bytes).
        assert_eq!(&b[..3], &[0x02, 0x0C, 7]);
        assert_eq!(&b[b.len() - 2..], &[0, 0]);
        assert_eq!(Lldpdu::parse(&b), Ok(du));
        assert!(Lldpdu::parse(&b[..5]).is_err());
        assert!(Lldpdu::parse(&[]).is_err());
    }

    mod properties {
        use super::*;
        use proptest::collection::vec;
        use proptest::prelude::*;

        /// IEEE 802.1AB: chassis and port ID values of 1..=255 bytes with their subtype.
        fn id() -> impl Strategy<Value = (u8, Vec<u8>)> {
            (any::<u8>(), vec(any::<u8>(), 1..=255))
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn emit_then_parse_round_trips(chassis in id(), port in id(), ttl in any::<u16>()) {
                let du = Lldpdu { chassis, port, ttl };
                prop_assert_eq!(Lldpdu::parse(&du.emit()), Ok(du));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in vec(any::<u8>(), 0..64)) {
                let _ = Lldpdu::parse(&bytes);
            }
        }
    }
}
