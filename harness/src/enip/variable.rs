//! The bytes of EtherNet/IP frames whose values a device picks anew for every session or
//! connection, masked before transcripts are compared (`--snapshots`, `harness diff`): two runs
//! against the same device differ there without anything having changed.
//!
//! The harness's own choices (connection serials, its T→O connection ids, its sequence counts)
//! are derived per case and stay compared; see `serials.rs`.

use std::ops::Range;

use crate::bus::Variable;

/// The registry's entry for the bus.
pub(crate) const VARIABLE: Variable = Variable { bytes, decoded };

/// Length of the encapsulation header (CIP Vol 2 §2-3).
const HEADER: usize = 24;
/// Encapsulation commands (CIP Vol 2 §2-3.2) whose frames carry a session handle.
const COMMANDS: [u16; 7] = [0x0004, 0x0063, 0x0064, 0x0065, 0x0066, 0x006F, 0x0070];
/// Where the Message Router reply of a SendRRData starts: header, interface handle (4),
/// timeout (2), item count (2), Null Address item (4), Unconnected Data item header (4).
const RR_REPLY: usize = HEADER + 16;
/// Where the connection id of a SendUnitData's Connected Address item starts: header,
/// interface handle, timeout, item count, item type and length.
const UNIT_CONNECTION: usize = HEADER + 12;

/// The variable byte ranges of `frame`: an encapsulation message (TCP) or a class 0/1 I/O
/// frame (UDP, CIP Vol 2 §2-6.3).
fn bytes(frame: &[u8]) -> Vec<Range<usize>> {
    let word = |at: usize| {
        frame
            .get(at..at + 2)
            .map(|b| u16::from_le_bytes([b[0], b[1]]))
    };
    let mut ranges = Vec::new();
    if word(0) == Some(2) && word(2) == Some(0x8002) {
        // Sequenced Address item: the connection id (the O→T one is the target's) and the
        // producer's encapsulation sequence number; then the CIP sequence count.
        ranges.push(6..14);
        if word(14) == Some(0x00B1) {
            ranges.push(18..20);
        }
    } else if frame.len() >= HEADER && word(0).is_some_and(|c| COMMANDS.contains(&c)) {
        // The session handle the target handed out at RegisterSession.
        ranges.push(4..8);
        let reply_service = frame.get(RR_REPLY).copied();
        let status = frame.get(RR_REPLY + 2).copied();
        if word(0) == Some(0x006F)
            && matches!(reply_service, Some(0xD4 | 0xDB))
            && status == Some(0)
        {
            // Forward_Open reply: the O→T connection id the target picked.
            ranges.push(RR_REPLY + 4..RR_REPLY + 8);
        }
        if word(0) == Some(0x0070) && word(UNIT_CONNECTION - 4) == Some(0x00A1) {
            // Connected Address item: the connection id; the data item's sequence count.
            ranges.push(UNIT_CONNECTION..UNIT_CONNECTION + 4);
            ranges.push(UNIT_CONNECTION + 8..UNIT_CONNECTION + 10);
        }
    }
    ranges.retain(|r| r.end <= frame.len());
    ranges
}

/// A decoded line with the I/O sequence count masked (`I/O T→O count 25 (50 bytes)`).
fn decoded(line: &str) -> String {
    let Some(rest) = line.strip_prefix("I/O ") else {
        return line.to_string();
    };
    match rest.split_once("count ") {
        Some((before, after)) => {
            let rest = after.trim_start_matches(|c: char| c.is_ascii_digit());
            if rest.len() == after.len() {
                // No count, or masked already.
                return line.to_string();
            }
            format!("I/O {before}count ..{rest}")
        }
        None => line.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hex(s: &str) -> Vec<u8> {
        s.split_whitespace()
            .map(|b| u8::from_str_radix(b, 16).unwrap())
            .collect()
    }

    #[test]
    fn the_session_handle_and_the_targets_connection_id_are_variable() {
        let register = hex(
            "65 00 04 00 00 10 00 00 00 00 00 00 01 00 00 00 00 00 00 00 00 00 00 00 01 00 00 00",
        );
        assert_eq!(bytes(&register), vec![4..8]);
        let fo_reply = hex("6F 00 2E 00 00 10 00 00 00 00 00 00 04 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 02 00 00 00 00 00 B2 00 1E 00 D4 00 00 00 01 00 00 4E 01 00 43 53 01 00 48 4E 31 53 48 4E A0 0F 00 00 A0 0F 00 00 00 00");
        assert_eq!(bytes(&fo_reply), vec![4..8, 44..48]);
        // A refused Forward_Open names no connection.
        let mut refused = fo_reply.clone();
        refused[42] = 0x01;
        assert_eq!(bytes(&refused), vec![4..8]);
    }

    #[test]
    fn io_frames_mask_connection_id_and_sequence_numbers() {
        let io = hex("02 00 02 80 08 00 01 00 00 4E 19 00 00 00 B1 00 38 00 19 00 01 00");
        assert_eq!(bytes(&io), vec![6..14, 18..20]);
        assert_eq!(
            bytes(&io[..12]),
            Vec::<Range<usize>>::new(),
            "short: nothing past its end"
        );
        assert_eq!(bytes(b"not a frame"), Vec::<Range<usize>>::new());
    }

    #[test]
    fn decoded_io_lines_lose_their_count() {
        assert_eq!(
            decoded("I/O T→O count 25 (50 bytes)"),
            "I/O T→O count .. (50 bytes)"
        );
        assert_eq!(decoded("RegisterSession"), "RegisterSession");
        let once = decoded("I/O O→T count 7 (50 bytes)");
        assert_eq!(decoded(&once), once, "masking twice changes nothing");
    }
}
